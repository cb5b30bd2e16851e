"""An independent solution of a yielding shear building under ground motion, for the tests: scipy's solve_ivp.

Nothing here comes from the engine.  Each storey is a hardening spring b k in parallel with a perfectly plastic
element of stiffness (1 - b) k and yield drift d_y, less P-delta's P/h; the building's damping matrix is given.
The integration is restarted at every record sample (the ground acceleration is linear between samples) and at
every yield and unloading event, which solve_ivp locates by root finding on its dense output; between them the
equations are linear and smooth, which DOP853 at a tight tolerance integrates to about 1e-11.  Each drift's
extrema are events too, so the peak drifts are read where the drift velocity vanishes, not from samples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

RTOL = 1e-12


@dataclass
class Storeys:
    """The storeys' law: elastic stiffness, hardening ratio, yield drift and P-delta's stiffness, per storey."""

    k: np.ndarray
    b: np.ndarray
    dy: np.ndarray
    g: np.ndarray


def _drifts(x: np.ndarray) -> np.ndarray:
    return np.diff(np.concatenate([[0.0], x]))


def _forces(u: np.ndarray, st: Storeys, branch: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Each storey's shear: b k u + (1 - b) k (u - p) elastic, b k u + s (1 - b) k d_y yielding; less P u / h."""
    plastic = np.where(branch == 0, st.k * (1 - st.b) * (u - p), branch * (1 - st.b) * st.k * st.dy)
    return st.b * st.k * u + plastic - st.g * u


def _rhs(mass, damping, st, branch, p, a0, a1, t0):
    n = len(mass)

    def f(t, y):
        q, v = y[:n], y[n:]
        shear = _forces(_drifts(q), st, branch, p)
        floor = -shear + np.append(shear[1:], 0.0)
        acc = (floor - damping @ v) / mass - (a0 + a1 * (t - t0))
        return np.concatenate([v, acc])
    return f


def _events(n, st, branch, p):
    """Yield surfaces of elastic storeys, drift-velocity zeros of yielding ones (terminal), and every drift's
    extremum (not terminal), as solve_ivp event functions; each with what it means."""
    evs, meaning = [], []
    for i in range(n):
        def drift(y, i=i):
            return y[i] - (y[i - 1] if i else 0.0)

        def drift_v(y, i=i):
            return y[n + i] - (y[n + i - 1] if i else 0.0)
        if branch[i] == 0:
            for s in (1, -1):
                e = (lambda t, y, s=s, drift=drift, i=i: s * (drift(y) - p[i]) - st.dy[i])
                e.terminal, e.direction = True, 1
                evs.append(e)
                meaning.append(("yield", i, s))
        else:
            e = (lambda t, y, s=branch[i], drift_v=drift_v: s * drift_v(y))
            e.terminal, e.direction = True, -1
            evs.append(e)
            meaning.append(("unload", i, branch[i]))
        e = (lambda t, y, drift_v=drift_v: drift_v(y))
        e.terminal, e.direction = False, 0
        evs.append(e)
        meaning.append(("extremum", i, 0))
    return evs, meaning


def solve(mass, damping, st: Storeys, accel: np.ndarray, dt: float, t_end: float | None = None) -> dict:
    """Peak drifts, final plastic offsets, plastic work and yield events of the building under the ground
    acceleration `accel` (sampled every dt, linear between samples, zero after), from rest."""
    n = len(mass)
    y = np.zeros(2 * n)
    branch = np.zeros(n, dtype=int)
    p = np.zeros(n)
    peak = np.zeros(n)
    work = 0.0
    yields = 0
    t_end = t_end if t_end is not None else (len(accel) - 1) * dt
    scale = st.dy.max() if np.all(np.isfinite(st.dy)) else 1.0
    t = 0.0
    k = 0
    while t < t_end * (1 - 1e-14):
        t_next = min((k + 1) * dt, t_end)
        if k + 1 < len(accel):
            a0, a1 = accel[k] + (accel[k + 1] - accel[k]) * (t - k * dt) / dt, (accel[k + 1] - accel[k]) / dt
        else:
            a0, a1 = 0.0, 0.0
        evs, meaning = _events(n, st, branch, p)
        sol = solve_ivp(_rhs(mass, damping, st, branch, p, a0, a1, t), (t, t_next), y, method="DOP853",
                        rtol=RTOL, atol=RTOL * scale * 1e-3, events=evs)
        for (kind, i, _), ys in zip(meaning, sol.y_events):
            if kind == "extremum" and len(ys):
                peak[i] = max(peak[i], np.max(np.abs(ys[:, i] - (ys[:, i - 1] if i else 0.0))))
        y_end = sol.y[:, -1].copy()
        u_end = _drifts(y_end[:n])
        for i in range(n):
            if branch[i] != 0:  # the plastic offset followed the drift
                p_new = u_end[i] - branch[i] * st.dy[i]
                work += (1 - st.b[i]) * st.k[i] * st.dy[i] * branch[i] * (p_new - p[i])
                p[i] = p_new
        peak = np.maximum(peak, np.abs(u_end))
        t_stop = sol.t[-1]
        if sol.status == 1:  # a terminal event
            fired = [j for j, te in enumerate(sol.t_events) if meaning[j][0] != "extremum" and len(te)]
            j = min(fired, key=lambda j: sol.t_events[j][0])
            kind, i, s = meaning[j]
            if kind == "yield":
                branch[i] = s
                p[i] = u_end[i] - s * st.dy[i]
                yields += 1
            else:
                branch[i] = 0
        else:
            k += 1
        y = y_end
        t = t_stop if sol.status == 1 else t_next
    return {"peak_drifts": peak, "plastic_offsets": p, "plastic_work": work, "yield_events": yields,
            "final_q": y[:n]}
