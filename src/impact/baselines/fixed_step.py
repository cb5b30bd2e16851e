"""Fixed-step classical RK4 baseline with interpolated impact location.

Each phase of the motion (free flight, sliding with friction, both masses stuck
together) is the affine ODE ``z' = A z + c + F sin(r t + phase)``, advanced with
classical 4-stage Runge--Kutta steps of size ``dt`` (the last step is cut at
t_end).

Walls: when a free-flight step ends with |s| > d/2, the crossing is located at
the first outward root of the cubic Hermite interpolant of s over the step
(end values s, s' of the step; all exact RK4 quantities), the step is redone
from its start with the partial length up to that root, the mass is put
exactly on the wall and Eq. 3 is applied; stepping then continues with full
steps from the impact time (the grid is not realigned).  A trajectory that
leaves and re-enters the clearance within one step is not seen (inherent to
the method; it needs dt small compared with the shortest flight).

Other switching events (end of sliding s' = 0, release of a stuck mass when the
contact / friction force it needs changes sign) are located by regula falsi
(Illinois) on redone partial RK4 steps.  Chatter / e = 0 as in
:mod:`impact.baselines.ivp`: rebounds slower than ``v_stick`` or lower than
``h_stick * (|x| + d/2)`` merge the masses.

Amplitude: trapezoid rule on x^2 at the step points over the window (a step
straddling t_window is cut with x interpolated linearly): second order in dt,
so the amplitude is the least accurate output of this method.
``nfev`` = 4 per RK4 step, including redone partial steps and root-search steps.
"""

from __future__ import annotations

import math

import numpy as np

from impact.baselines._common import (
    H_STICK,
    ZENO_IMPACTS,
    Affine,
    ImpactLog,
    TrapzWindow,
    check_inputs,
    default_v_stick,
    free_affine,
    impact_law,
    initial_state,
    leaves_now,
    make_result,
    merged_velocity,
    rebound_negligible,
    start_mode,
    stuck_affine,
    stuck_exit_functionals,
)
from impact.model.params import System

MAX_IDLE_STEPS = 1000


def _rhs_of(aff: Affine, r: float, ph: float):
    a10, a11, a12, a13 = (float(v) for v in aff.A[1])
    a30, a31, a32, a33 = (float(v) for v in aff.A[3])
    c1, c3 = float(aff.c[1]), float(aff.c[3])
    f1, f3 = float(aff.F[1]), float(aff.F[3])
    sin = math.sin

    def rhs(t, x, xd, y, yd):
        sn = sin(r * t + ph)
        return (xd, a10 * x + a11 * xd + a12 * y + a13 * yd + c1 + f1 * sn,
                yd, a30 * x + a31 * xd + a32 * y + a33 * yd + c3 + f3 * sn)

    return rhs


def rk4_step(rhs, t, z, h):
    x, xd, y, yd = z
    k1 = rhs(t, x, xd, y, yd)
    h2 = 0.5 * h
    k2 = rhs(t + h2, x + h2 * k1[0], xd + h2 * k1[1], y + h2 * k1[2], yd + h2 * k1[3])
    k3 = rhs(t + h2, x + h2 * k2[0], xd + h2 * k2[1], y + h2 * k2[2], yd + h2 * k2[3])
    k4 = rhs(t + h, x + h * k3[0], xd + h * k3[1], y + h * k3[2], yd + h * k3[3])
    h6 = h / 6.0
    return (x + h6 * (k1[0] + 2.0 * (k2[0] + k3[0]) + k4[0]),
            xd + h6 * (k1[1] + 2.0 * (k2[1] + k3[1]) + k4[1]),
            y + h6 * (k1[2] + 2.0 * (k2[2] + k3[2]) + k4[2]),
            yd + h6 * (k1[3] + 2.0 * (k2[3] + k3[3]) + k4[3]))


def hermite_crossing(s0: float, v0: float, s1: float, v1: float, h: float, side: int, half: float):
    """First time tau in (0, h] where the cubic Hermite interpolant of s crosses side*s = half outward.

    s0, v0 / s1, v1: s and s' at the start / end of the step; side * s1 > half is assumed.
    """
    hv0, hv1 = h * v0, h * v1
    # p(u) - side*half on u in [0, 1], times side
    a3 = side * (2.0 * s0 + hv0 - 2.0 * s1 + hv1)
    a2 = side * (-3.0 * s0 - 2.0 * hv0 + 3.0 * s1 - hv1)
    a1 = side * hv0
    a0 = side * s0 - half

    def g(u):
        return ((a3 * u + a2) * u + a1) * u + a0

    def dg(u):
        return (3.0 * a3 * u + 2.0 * a2) * u + a1

    best = None
    coeffs = np.array([a3, a2, a1, a0])
    if np.any(coeffs[:3] != 0.0):
        for root in np.roots(coeffs):
            if abs(root.imag) > 1e-9 * max(1.0, abs(root.real)):
                continue
            u = float(root.real)
            if not (0.0 < u <= 1.0 + 1e-12):
                continue
            if dg(u) <= 0.0:  # inward crossing or tangency: not a hit
                continue
            if best is None or u < best:
                best = u
    if best is None:
        # bisection on the cubic, g(0) treated as inside
        lo, hi = 0.0, 1.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if g(mid) > 0.0:
                hi = mid
            else:
                lo = mid
        best = hi
    else:
        for _ in range(3):  # Newton polish on the cubic
            d = dg(best)
            if d <= 0.0:
                break
            nxt = best - g(best) / d
            if not (0.0 < nxt <= 1.0):
                break
            best = nxt
    return min(best, 1.0) * h


def hermite_excursion(s0: float, v0: float, s1: float, v1: float, h: float, half: float) -> int:
    """Wall (+1/-1) that the cubic Hermite interpolant of s passes beyond inside the step, else 0."""
    hv0, hv1 = h * v0, h * v1
    a3 = 2.0 * s0 + hv0 - 2.0 * s1 + hv1
    a2 = -3.0 * s0 - 2.0 * hv0 + 3.0 * s1 - hv1
    a1 = hv0
    # critical points of p(u) = a3 u^3 + a2 u^2 + a1 u + s0 in (0, 1)
    crit = []
    if a3 != 0.0:
        disc = a2 * a2 - 3.0 * a3 * a1
        if disc >= 0.0:
            sq = math.sqrt(disc)
            crit = [(-a2 + sq) / (3.0 * a3), (-a2 - sq) / (3.0 * a3)]
    elif a2 != 0.0:
        crit = [-a1 / (2.0 * a2)]
    for u in sorted(crit):
        if 0.0 < u < 1.0:
            p = ((a3 * u + a2) * u + a1) * u + s0
            if abs(p) > half:
                return 1 if p > 0.0 else -1
    return 0


def locate(fun, h: float, f0: float, fh: float, tol: float) -> float:
    """Root in (0, h] of fun with f0 <= 0 < fh: Illinois regula falsi."""
    a, fa, b, fb = 0.0, min(f0, 0.0), h, fh
    side = 0
    c = b
    for _ in range(100):
        if fb == fa:
            break
        c = b - fb * (b - a) / (fb - fa)
        if not (a < c < b):
            c = 0.5 * (a + b)
        fc = fun(c)
        if fc > 0.0:
            b, fb = c, fc
            if side == 1:
                fa *= 0.5
            side = 1
        else:
            a, fa = c, fc
            if side == -1:
                fb *= 0.5
            side = -1
        if b - a <= tol * h or abs(fc) <= 1e-300:
            break
    return b


def simulate_rk4(system: System, r: float, t_end: float, t_window: float, start: str = "centre", *,
                 dt: float, max_impacts: int = 10 ** 6, v_stick: float | None = None,
                 h_stick: float = H_STICK):
    """Fixed-step RK4 with Hermite-interpolated impact location (see the module docstring).

    dt
        step size (model time units)
    max_impacts
        cap on impacts (plus merges); exceeding it fails the run
    v_stick
        rebound speed below which the masses merge (default 1e-7 * force_ratio)
    h_stick
        rebounds flying less high than h_stick * (abs(x) + d/2) also merge (default 1e-10)
    """
    check_inputs(system, r, t_end, t_window, start)
    dt = float(dt)
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt = {dt!r} must be positive")
    v_stick = default_v_stick(system, v_stick)
    mu, e, half = system.mu, system.e, 0.5 * system.gap
    af, ph = system.friction_accel, system.phase
    scale = max(system.force_ratio, 1e-300)
    log = ImpactLog()
    trapz = TrapzWindow(t_window)
    stuck = stuck_affine(system)
    stuck_rhs = _rhs_of(stuck, r, ph)
    free_cache: dict = {}

    def free_rhs(sf):
        if sf not in free_cache:
            aff = free_affine(system, sf)
            free_cache[sf] = (aff, _rhs_of(aff, r, ph))
        return free_cache[sf]

    z0, side = initial_state(system, start)
    z = tuple(float(v) for v in z0)
    t = 0.0
    nfev = n_steps = 0
    max_pen = -math.inf
    status = "ok"
    n_events = 0
    idle = 0
    mode = {"locked": ("locked",), "stick": ("stick", side), "free": ("free", 0.0)}[start_mode(system, side, af)]
    t_stop = t_end - 1e-12 * max(1.0, t_end)
    exits = None

    def accept(t0, za, t1, zb):
        nonlocal n_steps, max_pen
        n_steps += 1
        trapz.add(t0, za[0], t1, zb[0])
        pen = abs(zb[2] - zb[0]) - half
        if pen > max_pen:
            max_pen = pen

    max_pen = abs(z[2] - z[0]) - half

    while t < t_stop:
        h = min(dt, t_end - t)
        if idle > MAX_IDLE_STEPS:
            status = f"failed: no progress at t = {t:.6g} (accumulating events)"
            break

        if mode[0] == "locked":
            z1 = rk4_step(stuck_rhs, t, z, h)
            nfev += 4
            accept(t, z, t + h, z1)
            t, z = t + h, z1
            continue

        if mode[0] == "stick":
            sd = mode[1]
            if exits is None:  # entering the stuck phase
                s0 = sd * half if sd else z[2] - z[0]
                vc = merged_velocity(mu, z[1], z[3])
                z = (z[0], vc, z[0] + s0, vc)
                exits = stuck_exit_functionals(system, sd, s0)
                released = None
                for g, rel in exits:
                    if leaves_now(g, t, z, stuck, r, ph, scale):
                        released = rel
                        break
                if released is not None:
                    mode = ("free", -float(released) if af > 0.0 else 0.0)
                    exits = None
                    idle += 1
                    continue
            z1 = rk4_step(stuck_rhs, t, z, h)
            nfev += 4
            best = None
            for g, rel in exits:
                g1 = g(t + h, z1, r, ph)
                if g1 > 0.0:
                    cnt = [0]
                    zs, ts = z, t

                    def fun(tau, g=g, cnt=cnt, zs=zs, ts=ts):
                        cnt[0] += 1
                        return g(ts + tau, rk4_step(stuck_rhs, ts, zs, tau), r, ph)

                    tau = locate(fun, h, g(t, z, r, ph), g1, 1e-13)
                    nfev += 4 * cnt[0]
                    if best is None or tau < best[0]:
                        best = (tau, rel)
            if best is None:
                accept(t, z, t + h, z1)
                t, z = t + h, z1
                idle = 0
                continue
            tau, rel = best
            zc = rk4_step(stuck_rhs, t, z, tau)
            nfev += 4
            accept(t, z, t + tau, zc)
            idle = idle + 1 if tau <= 1e-12 * h else 0
            t, z = t + tau, zc
            mode = ("free", -float(rel) if af > 0.0 else 0.0)
            exits = None
            continue

        # free flight / sliding
        sf = mode[1]
        aff, rhs = free_rhs(sf)
        z1 = rk4_step(rhs, t, z, h)
        nfev += 4
        cands = []
        s1 = z1[2] - z1[0]
        wside = 0
        if abs(s1) > half:
            wside = 1 if s1 > 0.0 else -1
        elif (z[3] - z[1]) * (z1[3] - z1[1]) < 0.0:
            # s has an extremum inside the step: a brief excursion beyond a wall?
            wside = hermite_excursion(z[2] - z[0], z[3] - z[1], s1, z1[3] - z1[1], h, half)
        if wside:
            tau = hermite_crossing(z[2] - z[0], z[3] - z[1], s1, z1[3] - z1[1], h, wside, half)
            cands.append((tau, "wall", wside))
        if sf != 0.0 and -sf * (z1[3] - z1[1]) > 0.0:
            cnt = [0]
            zs, ts = z, t

            def fun(tau, cnt=cnt, zs=zs, ts=ts):
                cnt[0] += 1
                zz = rk4_step(rhs, ts, zs, tau)
                return -sf * (zz[3] - zz[1])

            tau = locate(fun, h, -sf * (z[3] - z[1]), -sf * (z1[3] - z1[1]), 1e-13)
            nfev += 4 * cnt[0]
            cands.append((tau, "slide", 0))
        if not cands:
            accept(t, z, t + h, z1)
            t, z = t + h, z1
            idle = 0
            continue
        tau, kind, wside = min(cands)
        zc = rk4_step(rhs, t, z, tau)
        nfev += 4
        accept(t, z, t + tau, zc)
        idle = idle + 1 if tau <= 1e-12 * h else 0
        t, z = t + tau, zc
        if kind == "slide":
            mode = ("stick", 0)
            exits = None
            continue
        x, xd, y, yd = z
        y = x + wside * half  # exactly on the wall
        rel = yd - xd
        if wside * rel < -v_stick:  # leaving already (interpolation artefact): carry on
            z = (x, xd, y, yd)
            continue
        n_events += 1
        if n_events > max_impacts:
            status = f"failed: more than max_impacts = {max_impacts} impacts by t = {t:.6g}"
            z = (x, xd, y, yd)
            break
        if wside * rel <= 0.0:
            z = (x, xd, y, yd)
            mode = ("stick", wside)
            exits = None
            continue
        xd2, yd2 = impact_law(mu, e, xd, yd)
        if rebound_negligible(system, r, t, (x, xd2, y, yd2), wside, v_stick, h_stick):
            xd2 = yd2 = merged_velocity(mu, xd, yd)
            mode = ("stick", wside)
            exits = None
        else:
            mode = ("free", math.copysign(1.0, yd2 - xd2) if af > 0.0 else 0.0)
        log.add(t, wside, (xd, yd), (xd2, yd2))
        z = (x, xd2, y, yd2)
        if log.zeno():
            status = (f"failed: unresolved impact accumulation at t = {t:.6g} "
                      f"(more than {ZENO_IMPACTS} close impacts; raise v_stick / h_stick)")
            break

    return make_result(log, t_end_req=t_end, t_reached=t, t_window=t_window, z=z, x2_integral=trapz.total,
                       nfev=nfev, n_steps=n_steps, max_pen=max_pen, status=status,
                       method=f"rk4 dt={dt:g}")
