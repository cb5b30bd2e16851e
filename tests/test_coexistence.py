"""Sweep modes and the initial-condition ensemble (coexisting steady states)."""

from __future__ import annotations

import numpy as np
import pytest

from impact.engine.run import simulate_system as simulate
from impact.engine.run import sweep
from impact.model.params import Protocol, System
from impact.stages.coexistence import count_attractors, ensemble_members, member_state, run_ensemble

PAPER = dict(mu=0.01, beta=0.0048, e=0.25)
SHORT = Protocol(periods=60, average_from=30)


def test_continuation_of_one_frequency_is_the_run_from_rest():
    system = System.from_gap_ratio("cid", gap_ratio=1.6, **PAPER)
    for mode in ("continuation_up", "continuation_down"):
        cont = sweep(system, [0.98], SHORT, mode=mode).runs[0]
        rest = simulate(system, 0.98, SHORT)
        assert cont.amplitude == rest.amplitude and cont.diagnostics == rest.diagnostics


def test_continuation_carries_the_state_and_the_force_phase():
    system = System.from_gap_ratio("cid", gap_ratio=1.6, **PAPER)
    up = sweep(system, [0.98, 1.0], SHORT, mode="continuation_up")
    first = up.runs[0]
    # the second frequency starts where the first ended, with a continuous force
    second = simulate(system.__class__(**{**system.as_dict(), "phase": np.remainder(0.98 * SHORT.t_end + np.pi, 2 * np.pi) - np.pi}),
                      1.0, SHORT, initial=first.final)
    assert up.runs[1].amplitude == pytest.approx(second.amplitude, rel=1e-12)
    assert up.runs[1].amplitude != simulate(system, 1.0, SHORT).amplitude


def _no_impact_cfg():
    return {"structure": {"beta": 0.0048, "force_ratio": 0.096},
            "protocol": {"periods": 200, "average_from": 100, "phase": 0.0,
                         "freq": {"min": 0.96, "max": 1.04, "step": 0.04},
                         "gap": {"min": 40.0, "max": 50.0, "step": 10.0},
                         "starts": {"cid": ["centre", "left"], "pid": ["centre"]}}}


def test_single_attractor_all_modes_and_members_agree():
    """A known single attractor: huge gap and friction strong enough to hold the mass.

    (A huge gap alone is not enough for the CID: a frictionless free mass with
    any momentum drifts into a wall sooner or later.)  Every member's relative
    motion stops on the floor at once, and the window starts late enough
    (beta t = 30) for each start's transient to decay far below 1e-9.
    """
    cfg = _no_impact_cfg()
    spec = {"damper": "cid", "mu": 0.01, "e": 0.25, "nu": 5.0}
    proto = Protocol(periods=2000, average_from=1000)
    members = ensemble_members(8, seed=3)
    ens = run_ensemble(cfg, spec, members, proto)
    amp = ens["amplitude"].values
    np.testing.assert_allclose(amp, np.broadcast_to(amp[:1], amp.shape), rtol=1e-9)
    assert int(ens["attractors_max"].max()) == 1
    system = System.from_gap_ratio("cid", gap_ratio=40.0, nu=5.0, **PAPER)
    r = ens["freq_ratio"].values
    for mode in ("from_rest", "continuation_up", "continuation_down"):
        got = sweep(system, r, proto, mode=mode).column("amplitude")
        np.testing.assert_allclose(got, amp[0, 0], rtol=1e-9)


def test_ensemble_is_deterministic():
    a = ensemble_members(10, seed=42)
    b = ensemble_members(10, seed=42)
    c = ensemble_members(10, seed=43)
    assert a.equals(b) and not a.equals(c)
    assert list(a["place"][:3]) == [0.0, -1.0, 1.0]  # the protocol's starts are members
    system = System.from_gap_ratio("cid", gap_ratio=1.6, **PAPER)
    for _, member in a.iterrows():
        state = member_state(system, member)
        assert abs(state.q[1] - state.q[0]) <= 0.5 * system.gap + 1e-12  # inside the clearance


def test_ensemble_finds_coexisting_attractors_where_the_starts_differ():
    """g = 1.6, r = 0.995: from the centre the mass never reaches the walls,
    from a wall it settles on the 2-EIPC orbit (see the closed-form check)."""
    system = System.from_gap_ratio("cid", gap_ratio=1.6, **PAPER)
    runs = [simulate(system, 0.995, Protocol(start=s)) for s in ("centre", "left")]
    amps = np.array([run.amplitude for run in runs])
    aipc = np.array([run.aipc for run in runs])
    assert count_attractors(amps, aipc) == 2
    assert count_attractors(np.array([1.0, 1.001]), np.array([2.0, 2.0])) == 1
