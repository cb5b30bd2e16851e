"""Event-driven baseline with ``scipy.integrate.solve_ivp`` between impacts.

The motion is split into smooth phases, each an affine ODE
``z' = A z + c + F sin(r t + phase)`` integrated by ``solve_ivp`` with terminal
events written as plain functions carrying ``terminal`` / ``direction``
attributes (scipy's event protocol):

free flight   events ``s - d/2`` and ``-s - d/2`` (direction +1: reaching a wall) and,
              with friction, ``s' = 0`` (end of sliding).  At a wall event Eq. 3 is
              applied, the position is put back exactly on the wall and the
              integration restarts.
stuck         both masses move as one (M + m); events: the contact force needed
              to hold the mass changes sign (at a wall) or exceeds the friction
              bound (interior stick, friction only).

Chatter and e = 0 are handled pragmatically: a rebound with relative speed below
``v_stick`` (default 1e-7 * force_ratio), or whose flight would rise less than
``h_stick * (|x| + d/2)`` (default 1e-10: below the position resolution of x and y
carried separately), merges the masses (momentum-conserving,
i.e. a plastic impact) into the stuck phase, which ends when the wall would
have to pull.  A fresh flight after a slow rebound starts with a first step of
a quarter of the predicted flight time, so the return to the wall cannot hide
inside the first step.

Robustness details (each found necessary on the paper's parameter ranges):
an event function that starts a phase at zero (to round-off or to the time
resolution of the event that began the phase) is shifted to start just on its
non-crossing side and held there at t0, so scipy neither reports a root at t0
nor a spurious one in the round-off right after it (and LSODA's interpolant,
which can be off at a step start, does not break the root bracket); a wall
crossing that begins and ends inside one solver step (x just exceeding d/2 at
its peak) is found from the extremum of s inside the step and located on the
dense output, instead of being skipped as sign-change detection at the step
ends would.  Every run is capped (``max_impacts``, and a cap on
consecutive phases that make no progress): a cap ends the run with status
``failed: ...``, never an endless loop.

Amplitude: the integral of x^2 over the window is taken on each solver step of
the dense output with an 8-point Gauss--Legendre rule (exact for the square of
DOP853's 7th-degree interpolant).  ``nfev`` counts every call of the
right-hand side (steps, dense-output stages); the implicit methods get the
exact constant Jacobian ``A``, so they spend no evaluations on finite differences.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from impact.baselines._common import (
    H_STICK,
    S_VEL,
    ZENO_IMPACTS,
    Affine,
    Functional,
    ImpactLog,
    after_phase,
    check_inputs,
    default_v_stick,
    free_affine,
    impact_law,
    initial_state,
    make_result,
    merged_velocity,
    near_zero,
    rebound_negligible,
    start_mode,
    stick_from,
    stuck_affine,
    stuck_exit_functionals,
    wall_gap,
)
from impact.model.params import System

IVP_METHODS = ("RK45", "DOP853", "Radau", "LSODA", "BDF", "RK23")
_IMPLICIT = ("Radau", "BDF", "LSODA")
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
#: phases in a row that end (almost) where they started before the run is called stuck
MAX_IDLE_PHASES = 200


def make_event(g: Functional, r: float, phase: float, direction: int, t0: float | None = None,
               z0=None, allowance: float = 0.0):
    """A scipy event function g(t, z) with terminal / direction attributes.

    With t0, z0 given (an event that starts at zero to within round-off) the function
    is shifted so that it starts at ``-direction * allowance`` (just on the side it is
    not crossing to) and is held there for t <= t0: scipy then neither reports a
    root at the start of the phase, nor finds a spurious sign change in the
    round-off right after it, nor trips over an interpolant that is slightly off at
    the step start (LSODA); excursions smaller than ``allowance`` (round-off level)
    are ignored.
    """
    w0, w1, w2, w3 = (float(v) for v in g.w)
    c0, cf = float(g.w0), float(g.wf)
    sin = math.sin

    if t0 is None:
        def event(t, z):
            return w0 * z[0] + w1 * z[1] + w2 * z[2] + w3 * z[3] + c0 + cf * sin(r * t + phase)
    else:
        def value(t, z):
            return w0 * z[0] + w1 * z[1] + w2 * z[2] + w3 * z[3] + c0 + cf * sin(r * t + phase)

        at_t0 = -direction * allowance if direction else 0.0
        shift = value(t0, z0) - at_t0
        if at_t0 == 0.0:
            at_t0 = 1e-300  # direction 0: any side; only used for non-crossing checks

        def event(t, z):
            if t <= t0:
                return at_t0
            return value(t, z) - shift

    event.terminal = True
    event.direction = direction
    return event


class Segments:
    """Runs solve_ivp phase by phase and keeps the run's counters.

    Shared with :mod:`impact.baselines.penalty`.
    """

    def __init__(self, system: System, r: float, t_end: float, t_window: float,
                 method: str, rtol: float, atol, jac_for_implicit: bool = True):
        if method not in IVP_METHODS:
            raise ValueError(f"method = {method!r} is not supported: choose one of {', '.join(IVP_METHODS)}")
        if not (rtol > 0.0):
            raise ValueError("rtol must be positive")
        self.system, self.r, self.phase = system, float(r), float(system.phase)
        self.t_end, self.t_window = float(t_end), float(t_window)
        self.method, self.rtol = method, float(rtol)
        self.atol = float(rtol) * system.force_ratio if atol is None else atol
        self.jac = jac_for_implicit and method in _IMPLICIT
        self.nfev = 0
        self.n_steps = 0
        self.x2 = 0.0
        self.max_pen = -math.inf
        self.half = 0.5 * system.gap

    def run(self, aff: Affine, events: list, t0: float, z0: np.ndarray, first_step=None,
            graze: list | None = None):
        """Integrate one phase from (t0, z0) to the first terminal event or t_end.

        events: [(g, direction)] with g a :class:`Functional`; all terminal.
        graze: [(g, index)] wall functionals g (event ``events[index]``, direction +1)
        whose brief excursions above zero inside a single solver step must not be
        missed: at each extremum of s inside a step g is checked, and a positive
        extremum is traced back, on the dense output, to the crossing before it,
        which then ends the phase as event ``index`` (see :meth:`_missed_crossing`).

        Returns (t, z, fired, message): fired is the index of the event that ended
        the phase (None at t_end); message is None or the solver's failure message.
        """
        A, c, F = aff.A, aff.c, aff.F
        r, ph = self.r, self.phase
        sin = math.sin
        counter = [0]
        z0 = np.asarray(z0, float)

        def rhs(t, z):
            counter[0] += 1
            return A @ z + c + F * sin(r * t + ph)

        opts = {}
        if self.jac:
            opts["jac"] = lambda t, z: A
        if first_step is not None:
            opts["first_step"] = min(float(first_step), self.t_end - t0)
        specs = list(events)
        all_events = []
        for g, direction in specs:
            zero = near_zero(g, t0, z0, aff, r, ph)[0]
            if zero:
                # starts at zero (to round-off / event-time resolution): shift and pin it
                size = float(np.abs(g.w) @ np.abs(z0)) + abs(g.w0) + abs(g.wf)
                ev = make_event(g, r, ph, direction, t0, z0, 1e-13 * size + 1e-300)
            else:
                ev = make_event(g, r, ph, direction)
            all_events.append(ev)
        try:
            sol = solve_ivp(rhs, (t0, self.t_end), z0, method=self.method,
                            rtol=self.rtol, atol=self.atol, events=all_events or None,
                            dense_output=True, **opts)
        except ValueError as exc:  # scipy's event root bracket failed (interpolant off at a step start)
            self.nfev += counter[0]
            return t0, z0, None, f"{self.method} event location failed at t = {t0:.6g} ({exc})"
        self.nfev += counter[0]
        if sol.status == -1:
            return t0, np.asarray(z0, float), None, sol.message
        ts = sol.t
        t_stop = float(ts[-1])
        z_stop = sol.y[:, -1].copy()
        fired = None
        if sol.status == 1:
            for i, te in enumerate(sol.t_events[:len(events)]):
                if te.size and te[-1] == ts[-1]:
                    fired = i
                    break
        if graze:
            hit = self._missed_crossing(sol, graze, t_stop)
            if hit is not None:
                t_stop, fired = hit
                z_stop = sol.sol(t_stop)
        n_in = int(np.searchsorted(ts, t_stop, side="left"))  # step points before t_stop
        self.n_steps += n_in
        s = np.append(sol.y[2, :n_in] - sol.y[0, :n_in], z_stop[2] - z_stop[0])
        self.max_pen = max(self.max_pen, float(np.max(np.abs(s))) - self.half)
        self._quadrature(sol, t_stop)
        return t_stop, z_stop, fired, None

    def _missed_crossing(self, sol, graze, t_stop):
        """Earliest wall crossing hidden inside one solver step.

        For every step before t_stop in which s' changes sign (s has an extremum),
        the extremum is located on the dense output; if a wall functional is
        positive there (beyond round-off), the crossing before it is found by brentq.
        Done here rather than as a scipy event, whose root bracketing fails on
        LSODA's interpolant when s' is near zero at a step start.
        """
        ts = sol.t
        sp = sol.y[3] - sol.y[1]
        r, ph = self.r, self.phase
        interp = sol.sol

        def sdot(tt):
            zz = interp(tt)
            return zz[3] - zz[1]

        for i in range(len(ts) - 1):
            a = float(ts[i])
            if a >= t_stop:
                break
            b = min(float(ts[i + 1]), t_stop)
            if b <= a or sp[i] * sp[i + 1] > 0.0 or (sp[i] == 0.0 and sp[i + 1] == 0.0):
                continue
            fa, fb = sdot(a), sdot(b)
            if fa * fb < 0.0:
                te = brentq(sdot, a, b, xtol=1e-15 * max(1.0, abs(b)))
            else:  # interpolant off at an end: sample the step instead
                grid = np.linspace(a, b, 17)
                te = None
            best = None
            for g, index in graze:
                if te is None:
                    vals = [g(tt, interp(tt), r, ph) for tt in grid]
                    k = int(np.argmax(vals))
                    tk, gk = float(grid[k]), vals[k]
                else:
                    tk = te
                    gk = g(te, interp(te), r, ph)
                zk = interp(tk)
                size = float(np.abs(g.w) @ np.abs(zk)) + abs(g.w0)
                if gk <= 1e-12 * size:  # no excursion beyond round-off
                    continue

                def fun(tt, g=g):
                    return g(tt, interp(tt), r, ph)

                if fun(a) > 0.0 or tk <= a:
                    continue
                root = brentq(fun, a, tk, xtol=1e-15 * max(1.0, abs(tk)), rtol=4 * np.finfo(float).eps)
                if best is None or root < best[0]:
                    best = (root, index)
            if best is not None:
                return best
        return None

    def _quadrature(self, sol, t_stop):
        ts = sol.t
        tw = self.t_window
        if t_stop <= tw or len(ts) < 2:
            return
        a = np.maximum(ts[:-1], tw)
        b = np.minimum(ts[1:], t_stop)
        keep = b > a
        a, b = a[keep], b[keep]
        if a.size == 0:
            return
        half = 0.5 * (b - a)
        nodes = (a + half)[:, None] + half[:, None] * _GL_X[None, :]
        x = sol.sol(nodes.ravel())[0].reshape(nodes.shape)
        self.x2 += float(np.sum(half[:, None] * _GL_W[None, :] * x * x))


def flight_first_step(system: System, aff: Affine, t: float, z, r: float, side: int):
    """A first step short enough to resolve a slow rebound's flight back to wall `side`."""
    v = z[3] - z[1]
    acc = aff.rate(t, np.asarray(z, float), r, system.phase)
    a = acc[3] - acc[1]
    if side * a > 0.0 and side * v < 0.0:
        tau = 2.0 * abs(v) / abs(a)
        if tau < 1.0:
            return max(0.25 * tau, 1e-14)
    return None


def simulate_ivp(system: System, r: float, t_end: float, t_window: float, start: str = "centre", *,
                 method: str = "DOP853", rtol: float = 1e-10, atol=None, max_impacts: int = 10 ** 6,
                 v_stick: float | None = None, h_stick: float = H_STICK):
    """Event-driven solve_ivp baseline (see the module docstring).

    method
        'RK45', 'DOP853', 'Radau', 'LSODA' (also 'BDF', 'RK23')
    rtol, atol
        solve_ivp tolerances; atol defaults to rtol * force_ratio
    max_impacts
        cap on wall impacts (plus merges); exceeding it fails the run
    v_stick
        rebound speed below which the masses merge (default 1e-7 * force_ratio)
    h_stick
        rebounds flying less high than h_stick * (abs(x) + d/2) also merge (default 1e-10)
    """
    check_inputs(system, r, t_end, t_window, start)
    seg = Segments(system, r, t_end, t_window, method, rtol, atol)
    v_stick = default_v_stick(system, v_stick)
    mu, e, half = system.mu, system.e, 0.5 * system.gap
    af = system.friction_accel
    ph = system.phase
    scale = max(system.force_ratio, 1e-300)
    log = ImpactLog()
    stuck = stuck_affine(system)
    walls = [(wall_gap(system, +1), +1), (wall_gap(system, -1), -1)]

    z, side = initial_state(system, start)
    t = 0.0
    status = "ok"
    n_events = 0
    idle = 0
    # mode: ('free', sf, first_step) or ('stick', side)
    mode = {"locked": ("locked",), "stick": ("stick", side), "free": ("free", 0.0, None)}[start_mode(system, side, af)]

    while t < t_end and status == "ok":
        if mode[0] == "locked":
            t, z, _, msg = seg.run(stuck, [], t, z)
            if msg:
                status = f"failed: {msg}"
            break

        if mode[0] == "stick":
            sd = mode[1]
            s0 = sd * half if sd else z[2] - z[0]
            exits = stuck_exit_functionals(system, sd, s0)
            t, z, released, msg, advanced = stick_from(system, seg, stuck, exits, t, z, s0, r, ph, scale)
            if msg or released is None:  # failed, or stuck to the end of the run
                status = f"failed: {msg}" if msg else status
                break
            if advanced is not None:
                idle = 0 if advanced else idle + 1
            # slide away with s' of sign -released (friction), or fly free (no friction)
            z[2] = z[0] + s0
            mode = ("free", -float(released) if af > 0.0 else 0.0, None)
            if idle > MAX_IDLE_PHASES:
                status = f"failed: no progress at t = {t:.6g} (sticking / release cycle)"
            continue

        # free flight (sliding with sign sf when friction acts)
        _, sf, fs = mode
        aff = free_affine(system, sf)
        ev_funcs = [(g, +1) for g, _ in walls]
        if sf != 0.0:
            # sliding ends when s' reaches zero: -sf * s' crosses zero upward
            ev_funcs.append((Functional(-sf * S_VEL), +1))
        t0 = t
        t, z, fired, msg = seg.run(aff, ev_funcs, t, z, fs, graze=[(g, i) for i, (g, _) in enumerate(walls)])
        stop, failure, idle = after_phase(msg, fired, t, t0, idle)
        if stop:
            status = failure or status
            break
        if idle > MAX_IDLE_PHASES:
            status = f"failed: no progress at t = {t:.6g} (accumulating events)"
            break
        if fired == 2:  # sliding stopped: try to stick
            mode = ("stick", 0)
            continue
        wside = walls[fired][1]
        z[2] = z[0] + wside * half  # put the mass exactly on the wall
        rel = z[3] - z[1]
        n_events += 1
        if n_events > max_impacts:
            status = f"failed: more than max_impacts = {max_impacts} impacts by t = {t:.6g}"
            break
        if wside * rel < -v_stick:
            # spurious root at the start of a phase (the mass is leaving this wall):
            # fly on with a first step short enough to see the way back
            n_events -= 1
            fs = flight_first_step(system, aff, t, z, r, wside) or 1e-6
            mode = ("free", sf, fs)
            continue
        if wside * rel <= 0.0:
            # grazing: let the stuck phase decide whether the wall holds the mass
            mode = ("stick", wside)
            continue
        pre = (z[1], z[3])
        xd, yd = impact_law(mu, e, z[1], z[3])
        if rebound_negligible(system, r, t, (z[0], xd, z[2], yd), wside, v_stick, h_stick):
            vc = merged_velocity(mu, z[1], z[3])
            xd = yd = vc
            mode = ("stick", wside)
        else:
            sf_new = math.copysign(1.0, yd - xd) if af > 0.0 else 0.0
            mode = ("free", sf_new, None)
        z[1], z[3] = xd, yd
        log.add(t, wside, pre, (xd, yd))
        if log.zeno():
            status = (f"failed: unresolved impact accumulation at t = {t:.6g} "
                      f"(more than {ZENO_IMPACTS} close impacts; raise v_stick / h_stick)")
        if mode[0] == "free":
            mode = ("free", mode[1], flight_first_step(system, free_affine(system, mode[1]), t, z, r, wside))

    return make_result(log, t_end_req=t_end, t_reached=t, t_window=t_window, z=z, x2_integral=seg.x2,
                       nfev=seg.nfev, n_steps=seg.n_steps, max_pen=seg.max_pen, status=status,
                       method=f"ivp {method} rtol={rtol:g}")
