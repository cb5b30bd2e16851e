"""Penalty (compliant-wall) baseline: a linear spring--dashpot at each wall.

While the damper mass is beyond a wall (penetration delta = side * s - d/2 > 0)
a contact force acts on it, F_c = -side (k delta + c delta'), and -F_c on the
structure.  The dashpot is calibrated so that an isolated contact returns the
coefficient of restitution e: with the reduced mass m_r = m M / (m + M)
(= mu / (1 + mu) in model units) the relative motion during contact is
m_r delta'' + c delta' + k delta = 0, which leaves delta = 0 after half a damped
period with velocity ratio exp(-zeta pi / sqrt(1 - zeta^2)); hence

    zeta = -ln e / sqrt(pi^2 + ln^2 e)   (zeta = 1 for e = 0),   c = 2 zeta sqrt(k m_r).

The contact phase ends at delta = 0 (as in that calibration; the linear dashpot
may pull briefly just before).  Free flight and contact are integrated by
``solve_ivp`` (stiff method by default) with events at contact entry
(delta = 0 upward) and exit (delta = 0 downward); both phases are affine, so the
implicit methods get the exact constant Jacobian.  Impact time = contact entry,
pre = velocities at entry, post = velocities at exit (NaN if the run ends in
contact); an entry slower than ``v_stick`` (a mass pressed into the wall from
rest, e.g. by friction) is a contact episode, not an impact.  With friction (CID) sliding / sticking is handled as in
:mod:`impact.baselines.ivp`, with the spring force included in the force a
stuck mass needs.  ``max_penetration`` is the largest delta at the solver's step
points.  Amplitude: Gauss--Legendre quadrature on the dense output, as for ivp.
"""

from __future__ import annotations

import math

from impact.baselines import _common as common
from impact.baselines.ivp import MAX_IDLE_PHASES, Segments
from impact.model.params import System


def dashpot(system: System, stiffness: float) -> tuple[float, float]:
    """(zeta, c): damping ratio and dashpot constant giving restitution e for stiffness k."""
    e = system.e
    if e <= 0.0:
        zeta = 1.0
    else:
        le = math.log(e)
        zeta = -le / math.sqrt(math.pi ** 2 + le * le)
    m_r = system.mu / (1.0 + system.mu)
    return zeta, 2.0 * zeta * math.sqrt(stiffness * m_r)


def simulate_penalty(system: System, r: float, t_end: float, t_window: float, start: str = "centre", *,
                     stiffness: float, method: str = "Radau", rtol: float = 1e-8, atol=None,
                     max_impacts: int = 10 ** 6, v_stick: float | None = None):
    """Compliant-contact baseline (see the module docstring).

    stiffness
        contact spring k (force per unit penetration, model units M = 1, omega = 1)
    method
        solve_ivp method ('Radau' default; 'LSODA', 'BDF', explicit ones work but are slow)
    rtol, atol
        solve_ivp tolerances; atol defaults to rtol * force_ratio
    max_impacts
        cap on contact entries; exceeding it fails the run
    v_stick
        entries slower than this (default 1e-7 * force_ratio; e.g. a mass pushed into the wall by friction from
        rest) are contact episodes, not impacts
    """
    common.check_inputs(system, r, t_end, t_window, start)
    k = float(stiffness)
    if not (math.isfinite(k) and k > 0.0):
        raise ValueError(f"stiffness = {stiffness!r} must be positive")
    if system.gap == 0.0:
        raise ValueError("the penalty method needs a clearance d > 0")
    _, cd = dashpot(system, k)
    seg = Segments(system, r, t_end, t_window, method, rtol, atol)
    v_stick = common.default_v_stick(system, v_stick)
    n_entries = 0
    half = 0.5 * system.gap
    af, ph = system.friction_accel, system.phase
    scale = max(system.force_ratio, 1e-300)
    log = common.ImpactLog()
    stuck = common.stuck_affine(system)

    z, side = common.initial_state(system, start)
    t = 0.0
    status = "ok"
    idle = 0
    open_impact = None  # index of the impact whose contact is in progress

    def contact_of(cs):
        return (cs, k, cd) if cs else None

    # initial phase: at a wall from rest the sign of s'' (or s''') decides contact or flight
    cside = 0
    if side != 0:
        aff0 = common.free_affine(system, 0.0)
        acc = aff0.rate(0.0, z, r, ph)
        jerk = aff0.rate2(0.0, z, r, ph)
        a_s, j_s = side * (acc[3] - acc[1]), side * (jerk[3] - jerk[1])
        if a_s > 1e-14 * scale or (abs(a_s) <= 1e-14 * scale and j_s > 0.0):
            cside = side
    mode = ("stick",) if af > 0.0 else ("move", 0.0)

    while t < t_end and status == "ok":
        if idle > MAX_IDLE_PHASES:
            status = f"failed: no progress at t = {t:.6g} (accumulating events)"
            break
        if mode[0] == "stick":
            s0 = z[2] - z[0]
            cs = (1 if s0 > 0 else -1) if abs(s0) > half else 0
            exits = common.stuck_exit_functionals(system, 0, s0, contact_of(cs))
            t, z, released, msg, advanced = common.stick_from(system, seg, stuck, exits, t, z, s0, r, ph, scale)
            if msg or released is None:  # failed, or stuck to the end of the run
                status = f"failed: {msg}" if msg else status
                break
            idle = 0 if advanced else idle + 1
            z[2] = z[0] + s0
            cside = cs
            # a mass released at the wall from rest slides inward unless pushed outward
            mode = ("move", -float(released))
            continue

        sf = mode[1]
        aff = common.free_affine(system, sf, contact_of(cside))
        if cside == 0:
            events = [(common.wall_gap(system, +1), +1), (common.wall_gap(system, -1), +1)]
            tags = [("enter", +1), ("enter", -1)]
        else:
            events = [(common.wall_gap(system, cside), -1)]
            tags = [("exit", cside)]
        if sf != 0.0:
            events.append((common.Functional(-sf * common.S_VEL), +1))
            tags.append(("slide", 0))
        t0 = t
        graze = [(common.wall_gap(system, +1), 0), (common.wall_gap(system, -1), 1)] if cside == 0 else None
        t, z, fired, msg = seg.run(aff, events, t, z, graze=graze)
        stop, failure, idle = common.after_phase(msg, fired, t, t0, idle)
        if stop:
            status = failure or status
            break
        kind, wside = tags[fired]
        if kind == "enter":
            n_entries += 1
            if n_entries > max_impacts:
                status = f"failed: more than max_impacts = {max_impacts} impacts by t = {t:.6g}"
                break
            if wside * (z[3] - z[1]) > v_stick:
                open_impact = log.add(t, wside, (z[1], z[3]))
            cside = wside
        elif kind == "exit":
            if open_impact is not None:
                log.set_post(open_impact, (z[1], z[3]))
                open_impact = None
            cside = 0
        else:
            mode = ("stick",)

    max_pen = seg.max_pen
    return common.make_result(log, t_end_req=t_end, t_reached=t, t_window=t_window, z=z, x2_integral=seg.x2,
                       nfev=seg.nfev, n_steps=seg.n_steps, max_pen=max_pen, status=status,
                       method=f"penalty k={k:g} {method} rtol={rtol:g}")
