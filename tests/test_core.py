"""Physics of the exact event-driven core: each test can fail on a wrong model."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from reference import one_body_amplitude, oscillator, rms_amplitude
from scipy.optimize import brentq

from impact.engine import layout, paper, paper_loop
from impact.engine.run import simulate_system as simulate
from impact.engine.run import sweep
from impact.model.params import ParameterError, Protocol, System, frequency_grid
from impact.model.scene import State

PAPER = dict(mu=0.01, beta=0.0048, e=0.25)


def cid(g, **kw):
    args = {**PAPER, **kw}
    return System.from_gap_ratio("cid", gap_ratio=g, **args)


@pytest.fixture(scope="module")
def chatter_run():
    """Small gap: impacts, chatter and sticking in one 500-period run."""
    return simulate(cid(0.1), 1.0, record=200000)


@pytest.mark.parametrize("system,r", [
    (cid(1.0), 1.0),                       # 2 IPC
    (cid(0.5, e=0.65), 0.97),              # irregular
    (cid(1.0, mu=0.03, e=0.0), 1.0),       # plastic impacts, sticking
    (System.from_gap_ratio("pid", gap_ratio=1.0, rp=1.0, **PAPER), 1.0),
])
def test_impact_law_conserves_momentum_and_reverses_relative_velocity(system, r):
    res = simulate(system, r, Protocol(periods=100, average_from=50), record=100000)
    rec = res.records
    assert len(rec["t"]) > 50
    mu, e = system.mu, system.e
    p_before = rec["v_minus"] + mu * rec["w_minus"]
    p_after = rec["v_plus"] + mu * rec["w_plus"]
    scale = np.abs(rec["v_minus"]) + mu * np.abs(rec["w_minus"])
    assert np.max(np.abs(p_after - p_before) / scale) <= 1e-14 * 4
    rel_before = rec["w_minus"] - rec["v_minus"]
    rel_after = rec["w_plus"] - rec["v_plus"]
    bounced = rec["stuck"] == 0
    # a rebound below the sticking threshold ends with a common velocity instead
    np.testing.assert_allclose(rel_after[bounced], -e * rel_before[bounced],
                               rtol=1e-14 * 8, atol=1e-15 * np.max(np.abs(rel_before)))
    # impacts happen with the masses approaching the wall they hit
    assert np.all(rec["side"] * rel_before > 0)


@pytest.mark.parametrize("system,r", [
    (cid(1.0), 1.0),
    (cid(0.5, e=0.65), 0.97),
    (cid(1.0, mu=0.03, e=0.0), 1.0),
    (System.from_gap_ratio("pid", gap_ratio=1.0, rp=0.5, **PAPER), 1.0),
])
def test_energy_balance_over_500_periods(system, r):
    res = simulate(system, r)
    d = res.diagnostics
    assert d["impacts"] > 100
    assert abs(d["energy_residual"]) <= 1e-9
    # the balance is not trivially satisfied: losses are a large share of the input
    assert d["impact_losses"] > 0.05 * d["work_input"] or system.e == 1.0


def test_energy_balance_with_chatter_and_sticking(chatter_run):
    d = chatter_run.diagnostics
    assert d["sticking_episodes"] > 100 and d["impacts"] > 1000
    assert abs(d["energy_residual"]) <= 1e-9
    assert not d["event_cap_reached"]


@pytest.mark.parametrize("r", [0.9, 0.97, 1.0, 1.06])
def test_huge_gap_reproduces_the_linear_structure(r):
    system = cid(50.0)
    proto = Protocol()
    res = simulate(system, r, proto)
    assert res.diagnostics["impacts"] == 0
    ref = rms_amplitude(lambda t: oscillator(t, 0.0, 0.0, 1.0, 2 * system.beta, system.force_ratio, r),
                        proto.t_window, proto.t_end)
    assert res.amplitude == pytest.approx(ref, rel=1e-9)


@pytest.mark.parametrize("kind,r", [("cid", 1.0), ("cid", 0.95), ("pid", 1.0)])
def test_zero_gap_is_one_mass(kind, r):
    system = System(kind, gap=0.0, rp=1.0 if kind == "pid" else 0.0, **PAPER)
    proto = Protocol()
    res = simulate(system, r, proto)
    ref = one_body_amplitude(system, r, proto)
    assert res.amplitude == pytest.approx(ref, rel=1e-9)
    assert np.isfinite(res.amplitude) and res.diagnostics["impacts"] == 0


def _paper_loop_amplitude(system, r: float, protocol: Protocol = Protocol()) -> float:
    """The paper loop called directly, below the dispatch and the System's ranges: a test of the loop itself."""
    diag = np.zeros(layout.NDIAG)
    z0, code = paper.initial_state(system, protocol.start)
    paper.ensure_compiled(system.kind)
    paper_loop.run(paper.param_vector(system, r, protocol), z0, code, paper.pid_data(system, r), None,
                   np.zeros((0, layout.NREC)), diag, np.zeros(4))
    return paper.window_amplitude(diag, protocol.t_window)[0]


def test_pid_tends_to_cid_as_the_pendulum_softens():
    """The paper loop's PID with a pendulum far softer than any scene's (MIN_TUNING) is the CID in the limit."""
    cid_amp = simulate(cid(1.0), 1.0).amplitude
    assert _paper_loop_amplitude(cid(1.0), 1.0) == cid_amp  # through the dispatch or not: the same bits
    diffs = []
    base = System.from_gap_ratio("pid", gap_ratio=1.0, rp=1.0, **PAPER)
    for rp in (1e-2, 1e-3):
        pid = SimpleNamespace(**{**base.as_dict(), "rp": rp})  # below the System's range, for the loop alone
        diffs.append(abs(_paper_loop_amplitude(pid, 1.0) - cid_amp) / cid_amp)
    assert diffs[1] <= 1e-6
    # the difference is the pendulum force, O(r'^2): it shrinks ~100x per decade
    assert diffs[1] < diffs[0] / 30


def _bare_x(system, z0, t):
    return oscillator(t, z0[0], z0[1], 1.0, 2 * system.beta, system.force_ratio, 0.8)


def test_brief_double_touch_inside_one_naive_step_is_caught():
    """The free mass rests just inside the wall; the structure's swing pushes
    s = y - x past d/2 for ~1e-4 time units, far less than any naive step."""
    system = System("cid", mu=0.01, beta=0.0048, e=0.5, gap=2.0)
    r = 0.8
    amp_swing = 1.0
    excess = 1e-8
    # start at x = +amp (velocity 0): s = y - x peaks when x is most negative
    z0 = np.array([amp_swing, 0.0, 1.0 - amp_swing + amp_swing - excess, 0.0])
    # choose y0 so that s(t) = y0 - x(t) just exceeds d/2 = 1 near x's first minimum
    t = np.linspace(0.0, 2 * np.pi, 2_000_001)
    xmin = _bare_x(system, z0, t).min()
    z0[2] = 1.0 + xmin + excess
    s = lambda tt: z0[2] - _bare_x(system, z0, tt) - 1.0
    vals = s(t)
    over = np.nonzero(vals > 0)[0]
    assert 0 < len(over) < 2000  # a brief touch: shorter than 1e-3 time units
    t_ref = brentq(s, t[over[0] - 1], t[over[0]], xtol=1e-15, rtol=1e-15)
    naive = s(np.arange(0.0, 2 * np.pi, 2 * np.pi / 64))  # 64 steps per period
    assert np.all(naive < 0)  # a sign check at step ends misses it
    res = simulate(system, r, Protocol(periods=1.0, average_from=0.5), record=10, initial=State.paper(z0))
    assert res.records["t"][0] == pytest.approx(t_ref, rel=1e-12, abs=1e-12)
    assert res.records["side"][0] == 1


@pytest.mark.parametrize("system", [
    cid(1.0, e=0.0), cid(1.0, e=1.0), cid(0.0), cid(1e-6), cid(1e-6, e=0.0),
    System.from_gap_ratio("pid", gap_ratio=1e-6, rp=1.0, **PAPER),
], ids=["e=0", "e=1", "d=0", "g=1e-6", "g=1e-6,e=0", "pid g=1e-6"])
def test_extreme_inputs_finish_finite(system):
    res = simulate(system, 1.0)
    d = res.diagnostics
    assert np.isfinite(res.amplitude) and np.isfinite(res.aipc)
    assert not d["event_cap_reached"]
    assert d["max_penetration"] < 1e-9 * max(system.gap, system.force_ratio)
    assert abs(d["energy_residual"]) <= 1e-9


def test_plastic_impacts_stick_and_release():
    res = simulate(cid(1.0, e=0.0), 1.0)
    d = res.diagnostics
    # every plastic impact ends in a sticking episode, which must end again
    assert d["sticking_episodes"] >= d["impacts"] - 5
    assert 0 < d["time_in_contact"] < Protocol().t_end


def test_event_cap_turns_into_a_flag():
    res = simulate(cid(0.1), 1.0, Protocol(periods=20, average_from=10, max_events_per_period=10))
    assert res.diagnostics["event_cap_reached"]
    assert math.isnan(res.amplitude)


def test_starting_wall_matters_only_through_the_state():
    centre = simulate(cid(1.0), 1.0, Protocol(start="centre"))
    left = simulate(cid(1.0), 1.0, Protocol(start="left"))
    # both land on the stable 2-EIPC orbit here: same amplitude, different transient
    assert left.amplitude == pytest.approx(centre.amplitude, rel=1e-6)
    assert left.diagnostics["impacts"] != centre.diagnostics["impacts"]


def test_sweep_reduces_to_x_max():
    system = cid(1.0)
    grid = frequency_grid(0.9, 1.1, 0.05)
    result = sweep(system, grid)
    amps = result.column("amplitude")
    assert result.x_max == amps.max()
    assert result.r_at_max in grid
    np.testing.assert_array_equal(grid, [0.9, 0.95, 1.0, 1.05, 1.1])


def test_refuses_bad_parameters():
    with pytest.raises(ParameterError, match="e = 1.5"):
        cid(1.0, e=1.5)
    with pytest.raises(ParameterError, match="gap_ratio"):
        cid(-1.0)
    with pytest.raises(ParameterError, match="kind"):
        System("tmd", gap=1.0, **PAPER)
    # a PID's r' in a scene's range, MIN_TUNING to MAX_TUNING, named as the paper names it
    for rp in (0.0, 0.05, 500.0):
        with pytest.raises(ParameterError, match=rf"^rp = {rp!r} is out of range: allowed \[0.1, 100.0\]"):
            System("pid", gap=1.0, rp=rp, **PAPER)
    with pytest.raises(ValueError, match="undamped resonance"):
        simulate(System("cid", mu=0.01, beta=0.0, e=0.5, gap=1.0), 1.0)
