"""Coulomb friction under the CID's mass (model.md, "Coulomb friction")."""

from __future__ import annotations

import numpy as np
import pytest
from reference import one_body_amplitude, oscillator_derivatives
from scipy.optimize import brentq

from impact.engine.run import simulate_system as simulate
from impact.model.params import Protocol, System

PAPER = dict(mu=0.01, beta=0.0048, e=0.25)


def _plate(system, r):
    """The structure's motion (x, x', x'') when the block is too light to matter (mu -> 0)."""
    return lambda t: oscillator_derivatives(t, 0.0, 0.0, 1.0, 2 * system.beta, system.force_ratio, r)


def _block_on_plate(plate, a_f, t_end, dt_scan=1e-3):
    """Independent stick-slip reference for a block on a plate moving as x(t).

    Sliding: y'' = -a_f sign(y' - x'), a parabola; sticking: y' = x' while the
    plate's acceleration |x''| <= a_f.  Phase ends: a scan, then Brent's method
    on the closed-form expressions.  Returns [(kind, t, y, y')].
    """
    xdd = lambda tt: plate(tt)[2]
    t, y, w, sigma, stuck = 0.0, 0.0, 0.0, 0, True
    events = []
    while t < t_end:
        grid = np.arange(t + dt_scan, t_end, dt_scan)
        if stuck:
            offset = y - plate(t)[0]
            vals = np.abs(xdd(grid)) - a_f
            hit = np.nonzero(vals > 0)[0]
            if not hit.size:
                break
            i = hit[0]
            sgn = np.sign(xdd(grid[i]))
            lo = grid[i - 1] if i else t
            t = brentq(lambda tt: xdd(tt) - sgn * a_f, lo, grid[i], xtol=1e-15, rtol=1e-15)
            x_t, v_t, _ = plate(t)
            y, w, sigma, stuck = x_t + offset, v_t, -int(sgn), False
            events.append(("slip", t, y, w))
        else:
            t0, y0, w0, sg = t, y, w, sigma
            srel = lambda tt: sg * ((w0 - sg * a_f * (tt - t0)) - plate(tt)[1])
            vals = srel(grid)
            hit = np.nonzero(vals <= 0)[0]
            if not hit.size:
                break
            i = hit[0]
            lo = grid[i - 1] if i else t0 + 0.5 * dt_scan
            t = brentq(srel, lo, grid[i], xtol=1e-15, rtol=1e-15)
            y = y0 + w0 * (t - t0) - 0.5 * sg * a_f * (t - t0) ** 2
            w = plate(t)[1]
            if abs(xdd(t)) <= a_f:
                stuck = True
                events.append(("stick", t, y, w))
            else:
                sigma = -sg
                events.append(("reverse", t, y, w))
    return events


LIGHT_BLOCK = System("cid", mu=1e-12, beta=0.0048, e=0.5, gap=1e6, nu=0.02)


def _until(t):
    return Protocol(periods=t / (2 * np.pi), average_from=0.0)


def test_block_on_harmonically_moving_plate_matches_stick_slip_reference():
    r = 0.9
    a_f = LIGHT_BLOCK.friction_accel
    events = _block_on_plate(_plate(LIGHT_BLOCK, r), a_f, 40.0)
    kinds = [k for k, *_ in events]
    assert "slip" in kinds and "stick" in kinds  # a real stick-slip case
    assert len(events) >= 6
    for kind, t_ev, y_ev, w_ev in events[:8]:
        # the block's position at each phase change, and its phase on each side
        at = simulate(LIGHT_BLOCK, r, _until(t_ev))
        assert at.final_state[2] == pytest.approx(y_ev, abs=1e-9), (kind, t_ev)
        before = simulate(LIGHT_BLOCK, r, _until(t_ev - 1e-5)).final_state
        after = simulate(LIGHT_BLOCK, r, _until(t_ev + 1e-5)).final_state
        rel_before, rel_after = before[3] - before[1], after[3] - after[1]
        if kind == "slip":
            assert rel_before == 0.0 and rel_after != 0.0, (kind, t_ev)
        elif kind == "stick":
            assert rel_before != 0.0 and rel_after == 0.0, (kind, t_ev)
        else:
            assert rel_before * rel_after < 0.0, (kind, t_ev)


@pytest.mark.parametrize("nu,g", [(0.05, 1.0), (0.2, 1.6), (0.5, 1.0)])
def test_energy_balance_includes_friction_work(nu, g):
    system = System.from_gap_ratio("cid", gap_ratio=g, nu=nu, **PAPER)
    res = simulate(system, 1.0, Protocol(start="left"))
    d = res.diagnostics
    assert d["friction_work"] > 0.01 * d["work_input"]
    assert abs(d["energy_residual"]) <= 1e-9


def test_no_friction_takes_the_frictionless_path():
    plain = System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER)
    a = simulate(plain, 1.0)
    b = simulate(System.from_gap_ratio("cid", gap_ratio=1.0, nu=0.0, **PAPER), 1.0)
    assert a.amplitude == b.amplitude and a.diagnostics == b.diagnostics
    # and the friction path converges to it as nu -> 0 (same stable orbit)
    tiny = simulate(System.from_gap_ratio("cid", gap_ratio=1.0, nu=1e-9, **PAPER), 1.0)
    assert tiny.amplitude == pytest.approx(a.amplitude, rel=1e-7)


@pytest.mark.parametrize("r", [0.95, 1.0])
def test_huge_friction_never_slides_and_is_one_mass(r):
    system = System.from_gap_ratio("cid", gap_ratio=1.0, nu=50.0, **PAPER)
    proto = Protocol()
    res = simulate(system, r, proto)
    ref = one_body_amplitude(system, r, proto)
    assert res.amplitude == pytest.approx(ref, rel=1e-9)
    assert res.diagnostics["impacts"] == 0 and res.diagnostics["friction_work"] == 0


def test_mass_released_at_rest_below_the_limit_stays_stuck():
    system = System.from_gap_ratio("cid", gap_ratio=1.0, nu=2.0, **PAPER)
    # the structure's acceleration never exceeds a_f here
    assert system.friction_accel > 10.0
    res = simulate(system, 1.0, Protocol(periods=50, average_from=25))
    z = res.final_state
    assert z[2] - z[0] == 0.0 and z[3] == z[1]
    assert res.diagnostics["time_in_contact"] == pytest.approx(2 * np.pi * 50)
