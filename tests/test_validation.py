"""Cross-validation of Eq. (4) against the virtual rig (impact.stages.validation.steps)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from impact.engine import layout, paper, run
from impact.engine.run import simulate_system as simulate
from impact.model.params import Protocol
from impact.outputs.measurements import load_measurements
from impact.outputs.signals import sweep_curve
from impact.rig import config as RC
from impact.rig import simulator as R
from impact.stages.validation import comparison as C
from impact.stages.validation import grid as G
from impact.stages.validation import paper_model as M
from impact.stages.validation.standalone import run_validation

# a short protocol: the tests check the machinery, not the paper's numbers
SHORT = {
    "protocol": {"periods": 60, "average_from": 30, "freq": {"min": 0.95, "max": 1.05, "step": 0.025}},
    "free_decay": {"x0_mm": [15.0], "duration_s": 10.0},
    "bare": {"settle_periods": 40, "record_periods": 10, "fine_freq": {"min": 0.998, "max": 1.002, "step": 0.001},
             "decay_x0_mm": [15.0], "decay_duration_s": 15.0},
    "figures": {"fig5a": {"mu": 0.0054, "gap_mm": 20.0, "rp": 1.0, "wall": "steel"},
                "fig5b": {"mu": 0.0054, "gap_mm": 20.0, "rp": 1.0, "wall": "rubber_1.0mm", "extra_r": [0.968]}},
}
ALL_OFF = {"nonlinear_pendulum": False, "finite_radius": False, "stiffness_scale": 1.0e4, "sensor": False}
IMPACTING = G.Case(0.0054, 20.0, 1.0, "cork_3.0mm")  # regular 2 impacts per cycle near r = 0.99


@pytest.fixture(scope="module")
def cfg():
    R.warm_up()
    return RC.validation_config(SHORT)


def test_grid_has_the_papers_108_cases():
    cases = G.all_cases(None)
    assert len(cases) == 108 and len({c.id for c in cases}) == 108
    assert G.Case.of(cases[5].id) == cases[5]
    assert G.frequency_values({"min": 0.9, "max": 1.1, "step": 0.01}).size == 21


def test_model_records_rebuilt_from_events_equal_the_kernel_sample_by_sample(cfg):
    """The paper loop's dense output (a forcing period's samples rebuilt from each call's impacts) against the loop
    called once per sample interval; and the model run through the entry point is that dense output."""
    ts = np.arange(3000, 4001) / 100.0
    omega = 2.0 * np.pi * float(cfg["structure"]["frequency_hz"])
    tm = ts * omega
    scene = M._model_scene(cfg, IMPACTING, 0.99, float(tm[-1]), forced=True, x0_mm=0.0)
    system = run.as_paper_system(scene)
    p = paper.run_parameters(system, 0.99, scene.t_end, 0.0, scene.max_events_per_period)
    paper.ensure_sampler_compiled()

    def sampled(chunk):
        return paper.dense_samples(p.copy(), paper.pid_data(system, 0.99), np.zeros(4), paper.FREE_FLIGHT, tm, chunk,
                                   1000)

    (dense, kept, *_), (stepwise, *_) = sampled(67), sampled(1)
    assert len(kept) > 20  # 2 impacts per cycle
    np.testing.assert_allclose(dense, stepwise, rtol=0, atol=1e-9)
    model = M._run_model(cfg, IMPACTING, 0.99, ts, forced=True)
    assert np.array_equal(model.x_mm, dense[:, 0]) and np.array_equal(model.s_mm, dense[:, 2] - dense[:, 0])
    assert np.array_equal(model.impact_times_s, kept[:, layout.R_T] / omega)


def test_model_record_amplitude_matches_the_production_protocol(cfg):
    """At r = 1 the forcing and natural periods coincide: the record's sqrt(2) RMS over the
    window equals the simulator's exactly integrated protocol amplitude (no detrending there)."""
    rec, _ = M.model_forced_point(cfg, IMPACTING, 1.0)
    assert rec.synthetic and rec.header["source"].startswith("model")
    exact = simulate(M.model_system(cfg, IMPACTING), 1.0, Protocol(periods=60, average_from=30))
    amp = sweep_curve([rec]).amplitude[0]
    assert exact.diagnostics["impacts_in_window"] > 20
    assert amp == pytest.approx(exact.amplitude, rel=2e-3)


def test_detect_beating():
    t = np.arange(0, 100, 0.01)
    steady = 2.0 * np.sin(2 * np.pi * 1.5 * t)
    beat = steady + 0.8 * np.sin(2 * np.pi * 1.55 * t)
    assert not C.detect_beating(t, steady, 1.5).beating
    b = C.detect_beating(t, beat, 1.5)
    assert b.beating and b.modulation == pytest.approx(0.8 / 2.0, rel=0.05)
    assert b.beat_period_s == pytest.approx(20.0, rel=0.15)
    # a monotone transient is not beating
    decay = np.exp(-0.02 * t) * steady
    assert not C.detect_beating(t, decay, 1.5).beating


def test_peak_of_sdof_curve():
    beta = 0.02
    r = np.round(np.arange(0.9, 1.1001, 0.01), 10)
    amp = 1 / np.sqrt((1 - r**2) ** 2 + (2 * beta * r) ** 2)
    xm, rk, rp = C.peak_of_curve(r, amp)
    assert rk == 0.99 or rk == 1.0
    assert rp == pytest.approx(math.sqrt(1 - 2 * beta**2), abs=1e-9)


def test_near_linear_rig_agrees_with_the_model(cfg):
    """Rig features off (linear point-mass pendulum, 10^4 x stiffer contact, ideal sensor):
    only the contact's finite duration remains; with impacts the errors are small."""
    res = C.run_case(cfg, IMPACTING, fidelity=ALL_OFF, r_values=[0.97, 0.99, 1.01])
    row = res.row
    assert row["model_aipc_true_at_max"] == pytest.approx(2.0, abs=0.05)
    for key in ("err_xmax_rel", "err_r_peak", "err_curve_rms_rel", "err_delta_rms"):
        assert math.isfinite(row[key]), key
    assert abs(row["err_xmax_rel"]) < 0.01
    assert abs(row["err_r_peak"]) < 1e-3
    assert row["err_curve_rms_rel"] < 0.01
    assert row["err_delta_rel"] < 0.01
    assert row["beating_agreement"] == 1.0


def test_full_rig_case_errors_are_finite_and_moderate(cfg):
    res = C.run_case(cfg, G.Case(0.0054, 40.0, 1.1, "steel"))
    row = res.row
    for key in ("err_xmax_rel", "err_r_peak", "err_curve_rms_rel", "err_delta_rms", "err_delta_rel"):
        assert math.isfinite(row[key]), key
    assert abs(row["err_xmax_rel"]) < 0.05
    assert row["err_delta_rel"] < 0.1
    assert {c["r"] for c in res.curve} == set(G.frequency_values(cfg["protocol"]["freq"]).tolist())


def test_run_validation_smoke_writes_everything(cfg, tmp_path):
    table = run_validation(SHORT, tmp_path, cases=[G.Case(0.0054, 20.0, 1.0, "steel")], processes=1)
    assert len(table) == 1
    for name in ("validation_table.csv", "validation_curves.csv", "validation_delta.csv", "drop_tests.csv",
                 "claims.json", "fig3.png", "fig3.pdf", "fig5.png", "fig5.pdf", "fig4_histories.png",
                 "fig3a_decay.csv", "fig3b_sweep.csv", "fig5a_decay.csv", "fig5b_sweep.csv"):
        assert (tmp_path / name).stat().st_size > 0, name
    claims = json.loads((tmp_path / "claims.json").read_text())
    assert {"beta_half_power", "delta_bare", "e_ordering", "beating_away_from_peaks", "fig5b",
            "agreement", "drop_tests", "run"} <= set(claims)
    assert claims["run"]["synthetic"] is True
    assert claims["drop_tests"]["max_abs_error_e"] < 0.01
    # the 0.01-type grid cannot resolve beta = 0.00048 (the analysis refuses it)
    assert claims["beta_half_power"]["half_power"]["paper_grid"]["rig"]["resolved"] is False
    recs = load_measurements(tmp_path / "records")
    assert recs and all(r.synthetic for r in recs)
    assert {r.header["source"].split(":")[0] for r in recs} >= {"model", "virtual rig (impact.rig.simulator)"}
    assert not list(tmp_path.rglob("*.tmp"))


def test_config_is_checked_and_the_shipped_yaml_matches_the_defaults():
    with pytest.raises(ValueError, match="unknown key"):
        RC.validation_config({"protocl": {}})
    with pytest.raises(ValueError, match="sensor"):
        RC.validation_config({"sensor": {"nosie_mm": 0.1}})
    with pytest.raises(ValueError, match="grid wall"):
        RC.validation_config({"grid": {"walls": ["glass"]}})
    from pathlib import Path

    import yaml

    path = Path(__file__).resolve().parents[1] / "config" / "validation.yaml"
    if not path.exists():
        pytest.skip("config/validation.yaml not present")
    cfg = RC.validation_config(yaml.safe_load(path.read_text()))
    assert cfg["grid"] and len(G.all_cases(cfg)) == 108


def test_a_filled_configuration_is_a_fresh_copy_every_call():
    """validation_config fills a configuration once per process; what it hands out must not be shared."""
    given = {"excitation": {"force_ratio_mm": 1e-4}}
    first = RC.validation_config(given)
    first["excitation"]["force_ratio_mm"] = 7.0
    first["grid"].clear()
    second = RC.validation_config(given)
    assert second["excitation"]["force_ratio_mm"] == 1e-4 and second["grid"]
    assert given == {"excitation": {"force_ratio_mm": 1e-4}}  # the input is not filled in place
    # a value JSON cannot carry unchanged (a tuple) is validated as given, not as its JSON list
    with pytest.raises(ValueError, match="grid"):
        RC.validation_config({"grid": {"walls": ("glass",)}})
    for _ in range(2):  # a bad configuration is refused every time, not only the first
        with pytest.raises(ValueError, match="unknown key"):
            RC.validation_config({"protocl": {}})


def test_the_workflow_runs_one_job_per_wall_and_refuses_cases_that_are_not_a_grid():
    """One job per wall material, each every setup (ball, gap, r') on it: the grid is such a product, the smoke
    subset must be one too, and a list that is not is refused naming what is missing."""
    walls, setups = G.batches(G.all_cases(None))
    assert len(walls) == 4 and len(setups) == 27
    assert G.batches(G.study_cases(RC.validation_config(None, smoke=True), smoke=True)) == (
        ["steel", "cork_3.0mm"], ["mu0.0252_d20_rp1"])
    with pytest.raises(ValueError, match="missing mu0.0054_d40_rp0.9_steel"):
        G.batches([G.Case(0.0252, 20.0, 1.0, "steel"), G.Case(0.0054, 40.0, 0.9, "cork_3.0mm")])
