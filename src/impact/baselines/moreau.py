"""Moreau--Jean event-capturing time stepping (nonsmooth contact dynamics).

Generalised coordinates q = (x, y), velocities v = (x', y'), mass matrix
M = diag(1, mu), smooth forces f(t, q, v) = -K q - C v + (f sin(r t + phase), 0)
with K = [[1 + mu rp^2, -mu rp^2], [-mu rp^2, mu rp^2]], C = diag(2 beta, 0).
One step of length h (theta method on the smooth forces):

    M (v+ - v) = h [theta f(t+h, q+, v+) + (1 - theta) f(t, q, v)] + G^T P
    q+         = q + h [theta v+ + (1 - theta) v]

G = (-1, 1) maps v to the relative velocity u = s' = y' - x'; P is the impulse
on the damper mass over the step (-P on the structure).  Because the forces are
linear, v+ = v_free + A^-1 G^T P with A = M + h theta C + h^2 theta^2 K, and
u+ = u_free + w P with the Delassus number w = G A^-1 G^T > 0.

Contacts (index set): wall +1 is active when its predicted gap
(d/2 - s) - gamma h u <= 0, wall -1 when (d/2 + s) + gamma h u <= 0 (gamma = 1/2
by default).  Velocity-level Newton law on each active wall:
u_N+ + e u_N- >= 0 _|_ lambda >= 0 with u_N = -u (right) or +u (left), u- the
velocity at the start of the step.  With Coulomb friction (CID, nu > 0) the
friction impulse is bounded by mu a_f h and opposes u+.  All of it acts on the
single relative velocity u, so the LCP (1-2 unilateral contacts plus friction)
has the closed-form solution

    u+ = clip(soft_threshold(u_free, w mu a_f h), L, U)

(L = -e u- if the left wall is active else -inf, U = -e u- if the right wall is
active else +inf): the minimiser of the convex 1-D problem
(u - u_free)^2 / (2 w) + mu a_f h |u| + indicator[L, U](u).

Impacts are not located in time: an impact is reported at the end time of a
step in which a wall impulse was applied (a jump of u above 1e-10 force_ratio; smaller
ones are round-off), with pre/post = v at the start/end of
that step; an impulse step counts as a new impact only if the mass was
approaching that wall at the start of the step, and consecutive impulse steps at
the same wall (persistent contact, e.g. e = 0, or a mass pressed against a wall
by friction) count as one impact.  Positions may penetrate the walls by O(h |u|);
``max_penetration`` reports it.  The scheme is first order with impacts (second
order for theta = 1/2 between impacts).  Amplitude: trapezoid rule on x^2 at the
step points.  ``nfev`` counts evaluations of the external force (one per step).
"""

from __future__ import annotations

import math

from impact.baselines._common import ImpactLog, TrapzWindow, check_inputs, initial_state, make_result
from impact.model.params import System


def _step_matrices(system: System, h: float, theta: float):
    mu, b, w2 = system.mu, system.beta, system.rp ** 2
    k11, k12, k22 = 1.0 + mu * w2, -mu * w2, mu * w2
    c11 = 2.0 * b
    ht, h2t2 = h * theta, (h * theta) ** 2
    a11 = 1.0 + ht * c11 + h2t2 * k11
    a12 = h2t2 * k12
    a22 = mu + h2t2 * k22
    det = a11 * a22 - a12 * a12
    i11, i12, i22 = a22 / det, -a12 / det, a11 / det
    w = i11 - 2.0 * i12 + i22
    return (k11, k12, k22, c11, i11, i12, i22, w)


def simulate_moreau_jean(system: System, r: float, t_end: float, t_window: float, start: str = "centre", *,
                         dt: float, theta: float = 0.5, gamma: float = 0.5):
    """Moreau--Jean time stepping (see the module docstring).

    dt
        time step
    theta
        theta-method weight of the smooth forces, in [0, 1] (1/2: trapezoidal; >= 1/2 stable)
    gamma
        gap prediction weight for the index set (contact active if g + gamma dt g' <= 0)
    """
    check_inputs(system, r, t_end, t_window, start)
    dt = float(dt)
    if not (math.isfinite(dt) and dt > 0.0):
        raise ValueError(f"dt = {dt!r} must be positive")
    if not (0.0 <= theta <= 1.0):
        raise ValueError(f"theta = {theta!r} must lie in [0, 1]")
    if not (0.0 <= gamma <= 1.0):
        raise ValueError(f"gamma = {gamma!r} must lie in [0, 1]")
    mu, e, half = system.mu, system.e, 0.5 * system.gap
    f, ph = system.force_ratio, system.phase
    af = system.friction_accel
    sin = math.sin
    log = ImpactLog()
    trapz = TrapzWindow(t_window)

    z0, _ = initial_state(system, start)
    x, xd, y, yd = (float(v) for v in z0)
    t = 0.0
    n = int(math.floor(t_end / dt + 1e-9))
    mats = _step_matrices(system, dt, theta)
    f_old = f * sin(ph)
    nfev = 1
    n_steps = 0
    max_pen = abs(y - x) - half
    last_side = 0  # wall that received an impulse in the previous step
    status = "ok"
    th1 = 1.0 - theta
    inf = math.inf
    tiny = 1e-10 * f  # velocity jumps below this are round-off, not impulses

    k = 0
    while True:
        if k < n:
            h = dt
            t1 = (k + 1) * dt
            m = mats
        else:
            h = t_end - t
            if h <= 1e-12 * max(1.0, t_end):
                break
            t1 = t_end
            m = _step_matrices(system, h, theta)
        k11, k12, k22, c11, i11, i12, i22, w = m
        f_new = f * sin(r * t1 + ph)
        nfev += 1
        # right-hand side of A v_free = M v + h[-K q - h theta (1-theta) K v - (1-theta) C v + F_theta]
        kq_x = k11 * x + k12 * y
        kq_y = k12 * x + k22 * y
        kv_x = k11 * xd + k12 * yd
        kv_y = k12 * xd + k22 * yd
        htt = h * theta * th1
        b_x = xd + h * (-kq_x - htt * kv_x - th1 * c11 * xd + theta * f_new + th1 * f_old)
        b_y = mu * yd + h * (-kq_y - htt * kv_y)
        vfx = i11 * b_x + i12 * b_y
        vfy = i12 * b_x + i22 * b_y
        u_free = vfy - vfx
        u_minus = yd - xd
        s = y - x
        # index set from the predicted gaps
        right = (half - s) - gamma * h * u_minus <= 0.0
        left = (half + s) + gamma * h * u_minus <= 0.0
        # friction: soft threshold with the impulse bound mu a_f h
        cf = w * mu * af * h
        if cf > 0.0:
            u_fr = math.copysign(max(abs(u_free) - cf, 0.0), u_free)
        else:
            u_fr = u_free
        lo = -e * u_minus if left else -inf
        hi = -e * u_minus if right else inf
        u_plus = min(max(u_fr, lo), hi) if lo <= hi else 0.5 * (lo + hi)
        # a wall impulse (beyond round-off) was applied?
        side = 0
        jump = u_plus - u_fr
        if abs(jump) > tiny + 1e-12 * abs(u_free):
            side = 1 if jump < 0.0 else -1
        P = (u_plus - u_free) / w
        # v+ = v_free + A^-1 G^T P, G^T = (-1, 1)
        nxd = vfx + P * (i12 - i11)
        nyd = vfy + P * (i22 - i12)
        nx = x + h * (theta * nxd + th1 * xd)
        ny = y + h * (theta * nyd + th1 * yd)
        if side != 0 and side != last_side and side * u_minus > tiny:
            log.add(t1, side, (xd, yd), (nxd, nyd))
        last_side = side
        trapz.add(t, x, t1, nx)
        x, xd, y, yd = nx, nxd, ny, nyd
        pen = abs(y - x) - half
        if pen > max_pen:
            max_pen = pen
        if not (math.isfinite(x) and math.isfinite(y)):
            status = f"failed: non-finite state at t = {t1:.6g}"
            t = t1
            break
        t = t1
        f_old = f_new
        n_steps += 1
        k += 1
        if k > n:
            break

    return make_result(log, t_end_req=t_end, t_reached=t, t_window=t_window, z=(x, xd, y, yd),
                       x2_integral=trapz.total, nfev=nfev, n_steps=n_steps, max_pen=max_pen,
                       status=status, method=f"moreau-jean dt={dt:g} theta={theta:g}")
