"""Buildings that yield: bilinear storeys with kinematic hardening and P-delta on the exact engine.

The engine is checked against an independent solution (tests/yield_reference.py: scipy's solve_ivp restarted at
every record sample and every yield and unloading event), against closed forms (the bilinear backbone of a slow
push, the rest a storey settles to), against its own elastic runs, and against its energy balance.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
import yield_reference as R

from impact.closed_form.pushover import pattern, pushover
from impact.engine.run import as_paper_system, simulate
from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.params import G_GRAV, ParameterError
from impact.model.records import load_record
from impact.model.scene import Damper, ForceRecord, GroundMotion, Harmonic, Scene

EL_CENTRO = load_record("elcentro")
AGREE = 1e-7  # the bar against the independent solution; both sides reach about 1e-11


def _reference(scene: Scene) -> dict:
    b = scene.building
    n = b.storeys
    weight_above = np.cumsum(b.masses[::-1])[::-1] * scene.gravity
    geometric = weight_above / b.storey_height if b.p_delta else np.zeros(n)
    st = R.Storeys(b.storey_stiffness, np.full(n, b.hardening), b.yield_drift, geometric)
    return R.solve(b.masses, b.damping, st, scene.load.accel, scene.load.dt, scene.t_end)


def _quake(building: Building, pga_g: float = 0.5, **kw) -> Scene:
    return Scene(building, kw.pop("dampers", ()), GroundMotion.from_record(EL_CENTRO, pga_g=pga_g), **kw)


CASES = {
    "one storey, perfectly plastic": Building.uniform(1, 1.0, 0.05).yielding(0.03, 0.0),
    "three storeys, hardening": Building.uniform(3, 1.0, 0.05).yielding(0.02, 0.05),
    "three storeys, hardening, P-delta": Building.uniform(3, 1.0, 0.05).yielding(0.02, 0.05, storey_height=3.0,
                                                                                p_delta=True),
}


@pytest.mark.parametrize("name", CASES)
def test_the_engine_matches_an_independent_solution_under_el_centro(name):
    scene = _quake(CASES[name])
    got = simulate_scene(scene).storeys
    ref = _reference(scene)
    assert got.yield_events.sum() == ref["yield_events"] > 0
    np.testing.assert_allclose(got.peak_drifts, ref["peak_drifts"], rtol=AGREE)
    dy = scene.building.yield_drift
    np.testing.assert_allclose(got.plastic_offsets, ref["plastic_offsets"], rtol=0, atol=AGREE * dy.max())
    assert got.plastic_work == pytest.approx(ref["plastic_work"], rel=AGREE)
    assert np.max(got.ductility) > 1.5  # the record drives the storeys well past yield


def _energy_residual(scene: Scene) -> float:
    return abs(simulate_scene(scene).diagnostics["energy_residual"])


@pytest.mark.parametrize("damper", [
    Damper("cid", mass=0.02 * 3e5, gap=0.04, e=0.6),
    Damper("tmd", mass=0.02 * 3e5, tuning=0.95, damping=0.1),
    Damper("pid", mass=0.02 * 3e5, gap=0.04, e=0.6, tuning=1.0, units=3),
], ids=["cid", "tmd", "pid"])
def test_energy_balances_with_yielding_storeys_and_a_damper(damper):
    building = Building.uniform(3, 1.0, 0.05).yielding(0.02, 0.03, storey_height=3.5, p_delta=True)
    result = simulate_scene(_quake(building, dampers=(damper,), collapse_drift_ratio=0.1))
    assert result.storeys.plastic_work > 0.0 and not result.storeys.collapsed
    assert abs(result.diagnostics["energy_residual"]) <= 1e-9
    if damper.kind == "cid":
        assert result.impacts > 0


@pytest.mark.parametrize("storeys, hardening, pga_g", [(1, 1.2e-4, 0.5), (1, 1.2e-4, 1.0), (3, 1.2e-4, 1.0),
                                                      (3, 2.5e-4, 1.0)])
def test_energy_balances_on_storeys_whose_post_yield_stiffness_is_near_zero(storeys, hardening, pga_g):
    """docs/model.md, "Near zero the flow loses digits": beside a post-yield stiffness of 1.2e-4 or 2.5e-4 k the
    rows' parts are far larger than the motion.  With the state read off the rows, these four runs balanced to
    -2.3e-9, -2.8e-9, 1.4e-9 and -1.6e-9; advanced mode by mode from the state (segment.flow_change), to 1e-10
    at most (and 40 such runs, one and three storeys at 1.2e-4 to 2e-3 k, 0.5 and 1 g, to 1.2e-10)."""
    building = Building.uniform(storeys, 1.0, 0.05).yielding(0.02, hardening)
    damper = Damper("cid", mass=0.05 * building.total_mass, gap=0.05, e=0.6)
    result = simulate(_quake(building, pga_g=pga_g, dampers=(damper,)), measures=("drifts",))
    assert result.storeys.plastic_work > 0.0 and result.impacts > 0
    assert abs(result.diagnostics["energy_residual"]) <= 1e-9


def test_yield_drifts_never_reached_give_the_elastic_run_to_round_off():
    elastic = Building.uniform(3, 0.8, 0.04)
    scene = _quake(elastic, pga_g=0.3)
    lin = simulate_scene(scene)
    high = simulate_scene(_quake(elastic.yielding(10.0, 0.1), pga_g=0.3))
    assert high.storeys.yield_events.sum() == 0
    np.testing.assert_allclose(high.peak_drifts, lin.peak_drifts, rtol=1e-12)
    assert high.peak_roof_acceleration == pytest.approx(lin.peak_roof_acceleration, rel=1e-12)


def test_a_slow_push_traces_the_bilinear_backbone():
    """A force ramped over 400 periods: the drift follows the static backbone u = F/k, then d_y + (F - k d_y)/(b k).

    It departs from it by the quasi-static lag c u'/k_t of each branch (k_t: k, then b k) and by the free vibration
    the kink starts, of amplitude (jump of u') / omega_b at the post-yield frequency omega_b = sqrt(b) omega; twice
    their sum is the bound.  A post-yield stiffness wrong by 1 % would miss the end of the ramp by 5 times it."""
    zeta, hb, dy = 0.05, 0.2, 0.01
    b = Building.uniform(1, 1.0, zeta, floor_mass=1.0).yielding(dy, hb)
    k, omega = b.storey_stiffness[0], b.omega1
    ramp, dt = 400.0, 0.05
    t = np.arange(0.0, ramp + dt / 2, dt)
    force = 3.0 * k * dy * t / ramp
    scene = Scene(b, (), ForceRecord(force, dt, distribution=(1.0,)))
    res = simulate(scene, ("samples",), times=t[1:])
    u = res.samples["q"][:, 0]
    backbone = np.where(force[1:] <= k * dy, force[1:] / k, dy + (force[1:] - k * dy) / (hb * k))
    rate = 3.0 * k * dy / ramp
    speed = rate / (hb * k)
    lag = 2.0 * zeta * omega * speed / (hb * k)
    ring = (speed - rate / k) / (math.sqrt(hb) * omega)
    np.testing.assert_allclose(u, backbone, rtol=0, atol=2.0 * (lag + ring))
    assert abs(u[-1] - backbone[-1]) < 0.2 * 0.01 * (backbone[-1] - dy)
    assert res.storeys.yield_events.sum() == 1


def test_a_storey_at_rest_settles_to_its_residual_drift():
    """After the record, free vibration to rest: each drift ends at (1 - b) p without P-delta, and at the P-delta
    equilibrium (1 - b) k p / (k - P/h) with it."""
    for p_delta in (False, True):
        b = Building.uniform(2, 0.5, 0.1).yielding(0.01, 0.1, storey_height=3.0, p_delta=p_delta)
        scene = _quake(b, pga_g=0.6, duration=EL_CENTRO.duration + 60.0)
        res = simulate_scene(scene)
        drifts = np.diff(np.concatenate([[0.0], res.final_q]))
        assert res.storeys.has_rest
        assert res.storeys.yield_events.sum() > 0 and np.all(np.abs(res.final_v) < 1e-9)
        np.testing.assert_allclose(drifts, res.storeys.residual_drifts, rtol=1e-6, atol=1e-9)


def test_a_run_the_event_cap_stops_names_the_storey_and_the_surface_it_stopped_at():
    """A bare building yielding back and forth under El Centro, the cap at 10 events a period: the run stops at
    a storey's event, and that storey is then where the event puts it (on its yield surface for a yield, the
    collapse limit never met)."""
    b = Building.uniform(3, 1.0, 0.05).yielding(0.002, 0.05)
    res = simulate_scene(_quake(b, pga_g=0.8, max_events_per_period=10))
    d = res.diagnostics
    assert d["stopped_by"] == "event cap" and d["stop_unit"] == -1
    assert d["stop_storey"] in (1, 2, 3) and d["stop_event"] in ("yield", "unload")
    i = d["stop_storey"] - 1
    drift = np.diff(np.concatenate([[0.0], res.final_q]))[i]
    if d["stop_event"] == "yield":
        assert drift - res.storeys.plastic_offsets[i] == pytest.approx(d["stop_side"] * 0.002, rel=1e-9)


def test_p_delta_beyond_the_post_yield_stiffness_collapses_and_stops_at_the_limit():
    """b k < P/h: past yield the storey's stiffness is negative, its mode grows, and the drift runs to the limit."""
    mass = 1e6
    b = Building.uniform(1, 1.5, 0.03, floor_mass=mass)
    height = 3.0
    geometric = mass * G_GRAV / height
    hb = 0.5 * geometric / b.storey_stiffness[0]  # post-yield stiffness b k - P/h = -P/(2h) < 0
    building = b.yielding(0.02, hb, storey_height=height, p_delta=True)
    res = simulate_scene(_quake(building, pga_g=1.0, collapse_drift_ratio=0.1))
    assert res.storeys.collapsed
    assert res.storeys.peak_drifts[0] == pytest.approx(0.1 * height, rel=1e-9)
    assert abs(res.diagnostics["energy_residual"]) <= 1e-9
    assert not res.storeys.has_rest  # P-delta outweighs the post-yield stiffness: the rest lies past the surface


def test_a_run_without_collapse_limit_reports_none():
    res = simulate_scene(_quake(CASES["three storeys, hardening"]))
    assert not res.storeys.collapsed and res.storeys.has_rest
    js = res.as_json()
    for key in ("peak_drifts_m", "residual_drifts_m", "plastic_offsets_m", "plastic_work_J", "yield_events",
                "ductility", "collapsed"):
        assert key in js
    assert len(js["peak_drifts_m"]) == 3


def test_a_yielding_building_never_runs_on_the_paper_loop():
    b = Building.paper(0.02)
    scene = Scene(b.yielding(0.5, 0.1), (Damper("cid", mass=0.05, gap=1.0, e=0.6),), Harmonic(0.1, 1.0),
                  duration=200.0)
    assert as_paper_system(scene) is None
    assert simulate(scene).loop == "scene"


@pytest.mark.parametrize("kw, field", [
    ({"yield_drift": -0.01}, "yield_drift[1]"),
    ({"yield_drift": [0.01, 0.02]}, "yield_drift has 2 values"),
    ({"yield_drift": 0.01, "hardening": 1.0}, "hardening"),
    ({"yield_drift": 0.01, "p_delta": True}, "p_delta needs storey_height"),
    ({"yield_drift": 0.01, "storey_height": 0.0}, "storey_height[1]"),
])
def test_bad_yield_input_is_refused_by_name(kw, field):
    with pytest.raises(ParameterError) as err:
        Building.uniform(3, 1.0, 0.05).yielding(**kw)
    assert field in str(err.value)


def test_a_building_that_can_fall_over_needs_a_collapse_limit_and_a_near_zero_stiffness_is_refused():
    b = Building.uniform(1, 1.5, 0.03, floor_mass=1e6)
    geometric = 1e6 * G_GRAV / 3.0
    soft = b.yielding(0.02, 0.5 * geometric / b.storey_stiffness[0], storey_height=3.0, p_delta=True)
    with pytest.raises(ParameterError, match="give collapse_drift_ratio"):
        _quake(soft)
    flat = b.yielding(0.02, geometric / b.storey_stiffness[0], storey_height=3.0, p_delta=True)
    with pytest.raises(ParameterError, match="post-yield stiffness"):
        _quake(flat, collapse_drift_ratio=0.1)


def test_the_post_yield_stiffness_is_b_k_less_the_weight_each_storey_carries_over_its_height():
    """Storey 1 carries both floors and the roof's damper, storey 2 the roof and its damper: b k - P/h each."""
    b = Building.explicit([2e5, 1e5], [8e7, 5e7], storey_damping=[1e5, 1e5])
    damper = Damper("cid", 3e3, gap=0.05, e=0.5)
    scene = _quake(b.yielding(0.02, 0.1, storey_height=[4.0, 3.0], p_delta=True), dampers=(damper,),
                   collapse_drift_ratio=0.1)
    carried = np.array([2e5 + 1e5 + 3e3, 1e5 + 3e3]) * G_GRAV
    np.testing.assert_allclose(scene.post_yield_stiffness(), 0.1 * np.array([8e7, 5e7]) - carried / [4.0, 3.0],
                               rtol=1e-15)
    assert _quake(b.yielding(0.02, 0.1)).post_yield_stiffness().tolist() == [8e6, 5e6]  # no P-delta: b k
    assert _quake(b).post_yield_stiffness() is None


def test_the_stability_coefficient_is_the_weight_carried_over_stiffness_times_height_dampers_included():
    """theta = P / (k h): the building's own (the collapse stage's archetypes) from its floors, a scene's with its
    dampers' weight too, both from the one formula on Building."""
    b = Building.explicit([2e5, 1e5], [8e7, 5e7], storey_damping=[1e5, 1e5]).yielding(
        0.02, 0.1, storey_height=[4.0, 3.0], p_delta=True)
    heights = np.array([4.0, 3.0])
    np.testing.assert_allclose(b.stability_coefficients(),
                               np.array([3e5, 1e5]) * G_GRAV / (np.array([8e7, 5e7]) * heights), rtol=1e-15)
    scene = _quake(b, dampers=(Damper("cid", 3e3, gap=0.05, e=0.5),), collapse_drift_ratio=0.1)
    np.testing.assert_allclose(scene.stability_coefficients(),
                               np.array([3.03e5, 1.03e5]) * G_GRAV / (np.array([8e7, 5e7]) * heights), rtol=1e-15)
    assert replace(b, p_delta=False).stability_coefficients().tolist() == [0.0, 0.0]


def test_a_perfectly_plastic_storey_needs_damping_and_collapse_needs_heights():
    undamped = Building.explicit([1.0], [1.0], storey_damping=[0.0])
    with pytest.raises(ParameterError, match="hardening = 0 without P-delta"):
        undamped.yielding(0.1, 0.0)
    with pytest.raises(ParameterError, match="collapse_drift_ratio needs"):
        _quake(Building.uniform(1, 1.0, 0.05).yielding(0.01), collapse_drift_ratio=0.1)


def test_a_one_storey_pushover_is_the_bilinear_backbone_with_p_delta():
    b = Building.uniform(1, 1.0, 0.05).yielding(0.02, 0.05, storey_height=3.0, p_delta=True)
    k, g = b.storey_stiffness[0], b.masses[0] * G_GRAV / 3.0
    curve = pushover(b, 0.1)
    assert curve.roof_drift.tolist() == pytest.approx([0.0, 0.02, 0.1], rel=1e-12)
    assert curve.base_shear[1] == pytest.approx((k - g) * 0.02, rel=1e-12)
    assert curve.base_shear[2] - curve.base_shear[1] == pytest.approx((0.05 * k - g) * 0.08, rel=1e-9)
    assert curve.yielding == [[], [1], [1]]


def test_a_three_storey_pushover_yields_its_first_storey_first_at_its_strength():
    """Without P-delta storey 1 carries the whole base shear, so it yields first, at V = k d_y, with the roof at
    V sum(S_i) / k; past it every storey's drift follows its own branch."""
    b = Building.uniform(3, 1.0, 0.05).yielding(0.02, 0.1)
    k = b.storey_stiffness[0]
    carried = np.cumsum(pattern(b, "triangular")[::-1])[::-1]
    curve = pushover(b, 0.2, "triangular")
    assert curve.base_shear[1] == pytest.approx(k * 0.02, rel=1e-12)
    assert curve.roof_drift[1] == pytest.approx(k * 0.02 * carried.sum() / k, rel=1e-12)
    assert curve.yielding[1] == [1]
    assert np.all(np.diff(curve.base_shear) > 0)  # hardening, no P-delta: the shear only grows


def test_quake_and_pushover_take_the_yield_flags_and_name_a_bad_one(capsys):
    from impact.cli import main
    main(["quake", "--record", "elcentro", "--pga-g", "0.4", "--storeys", "2", "--yield-drift-m", "0.01",
          "--hardening", "0.2", "--storey-height-m", "3", "--p-delta", "--collapse-drift-ratio", "0.1", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert len(out["ductility"]) == 2 and out["yield_events"] > 0 and out["collapsed"] is False
    assert out["plastic_work_J"] > 0
    for argv, flag in ((["quake", "--record", "elcentro", "--hardening", "0.1"], "--hardening needs --yield-drift-m"),
                       (["quake", "--record", "elcentro", "--yield-drift-m", "0.01", "--p-delta"], "--p-delta needs"),
                       (["pushover", "--roof-drift-m", "0.1"], "pushover needs --yield-drift-m")):
        with pytest.raises(SystemExit):
            main(argv)
        assert flag in capsys.readouterr().err
    main(["pushover", "--storeys", "2", "--yield-drift-m", "0.01", "--roof-drift-m", "0.1", "--hardening", "0.1",
          "--json"])
    curve = json.loads(capsys.readouterr().out)
    assert curve["roof_drift_m"][-1] == pytest.approx(0.1)


def test_the_ida_scales_a_run_only_for_a_linear_damper_on_an_elastic_building():
    from impact.stages.ida.plan import scales_linearly
    elastic = Building.uniform(3, 1.0, 0.05)
    tmd, cid = Damper("tmd", 1e3, tuning=0.98), Damper("cid", 1e3, gap=0.1, e=0.5)
    assert scales_linearly(elastic, ()) and scales_linearly(elastic, (tmd,))
    assert not scales_linearly(elastic, (cid,))
    assert not scales_linearly(elastic, (replace(tmd, stroke_limit=0.5),))  # its end stops strike
    assert not scales_linearly(elastic.yielding(0.02), ())
    assert not scales_linearly(elastic.yielding(0.02, 0.1, storey_height=3.0, p_delta=True), (tmd,))


def test_a_softening_pushover_loses_its_strength_where_the_closed_form_says():
    """b k < P/h: past yield the shear falls along b k - P/h and reaches zero at d_y + (k - P/h) d_y / (P/h - b k)."""
    b = Building.uniform(1, 1.5, 0.03, floor_mass=1e6)
    k, g = b.storey_stiffness[0], 1e6 * G_GRAV / 3.0
    hb = 0.5 * g / k
    curve = pushover(b.yielding(0.02, hb, storey_height=3.0, p_delta=True), 10.0)
    assert curve.ended == "no lateral strength left"
    assert curve.base_shear[1] == pytest.approx((k - g) * 0.02, rel=1e-12)
    assert curve.roof_drift[-1] == pytest.approx(0.02 + (k - g) * 0.02 / (g - hb * k), rel=1e-9)
    assert curve.base_shear[-1] == pytest.approx(0.0, abs=1e-9 * curve.base_shear[1])


def test_a_softening_storey_steeper_than_the_rest_of_the_building_ends_the_push_in_a_snap_back():
    """Two storeys, P-delta on a heavy roof: past yield the first storey's tangent b k - P1/h is negative and
    steeper than the elastic second storey's k - P2/h.  For the roof to move on, the shear would have to rise
    (1 / d lam = s1 / t1 + s2 / t2 > 0), which would move the yielding storey back: a snap-back, where roof
    displacement control cannot go.  The push ends there, at the first storey's yield."""
    k, h, dy = 1e8, 3.0, 0.01
    m = np.array([1e4, 0.8 * k * h / G_GRAV - 1e4])  # the first storey carries 0.8 k h of weight
    stiffness = np.array([[2 * k, -k], [-k, k]])
    b = Building(m, np.array([k, k]), 0.002 * stiffness).yielding(np.array([dy, 1.0]), 0.05, storey_height=h,
                                                                    p_delta=True)
    geometric = np.cumsum(m[::-1])[::-1] * G_GRAV / h
    s = np.cumsum(pattern(b, "first-mode")[::-1])[::-1]  # the share of the pattern each storey carries
    tangents = np.array([0.05 * k - geometric[0], k - geometric[1]])
    assert np.sum(s / tangents) > 0  # the condition for a snap-back at the first storey's yield
    curve = pushover(b, 0.5)
    assert curve.ended == "snap-back"
    yield_shear = (k - geometric[0]) * dy / s[0]
    assert curve.base_shear[-1] == pytest.approx(yield_shear, rel=1e-12)
    assert curve.roof_drift[-1] == pytest.approx(yield_shear * np.sum(s / (k - geometric)), rel=1e-12)
    assert curve.yielding[-1] == [1]
