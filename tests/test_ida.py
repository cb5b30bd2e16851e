"""The FEMA P695 suites, Sa(T1) on the exact core, and the incremental dynamic analysis stage."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest
import xarray as xr
from scipy import signal
from test_scene import _linear_roof

from impact.closed_form.tmd import tuned_for
from impact.engine.scenes import simulate_scene
from impact.engine.spectra import spectral_acceleration
from impact.model.building import Building
from impact.model.params import G_GRAV, ParameterError
from impact.model.records import Record, RecordError
from impact.model.scene import GroundMotion, Scene
from impact.model.suites import (
    GROUPS,
    load_suite_record,
    parse_key,
    record_by_key,
    stored_pseudo_acceleration,
    suite_keys,
)
from impact.stages import buildings
from impact.stages.ida import plan as IP
from impact.stages.ida import runs as IR
from impact.stages.ida import tables as IT

PERIODS = (0.5, 1.0, 2.0)   # the loads stage's fundamental periods
ALL_KEYS = suite_keys("farfield") + suite_keys("nearfield")
#: three ground motions of each suite, one per group of the near-field set
SAMPLE_KEYS = ("fema-farfield:1:a", "fema-farfield:12:b", "fema-farfield:22:a",
               "fema-nearfield:2:a", "fema-nearfield:14:b", "fema-nearfield:20:a")
LOADS = {"storeys": [1, 3], "periods_s": [1.0], "zeta": 0.02, "mass_ratios": [0.02], "e": 0.25}
IDA = {"suites": ["farfield", "nearfield"], "motions": ["fema-farfield:3:a", "fema-nearfield:1:b"],
       "sa_g": [0.1, 0.4], "design_sa_g": 0.4, "storey_height_m": 3.0, "stroke_limit_m": 1.0,
       "drift_limits": [0.005, 0.01],
       "verdict": {"improve": 0.1, "worsen": 0.05, "bootstrap": 300, "interval": 0.9, "seed": 1}}


def test_the_suites_hold_the_fema_p695_sets_with_their_groups():
    assert len(suite_keys("farfield")) == 44 and len(suite_keys("nearfield")) == 56
    groups = [load_suite_record(k).metadata["group"] for k in ALL_KEYS]
    assert {g: groups.count(g) for g in GROUPS} == {"far-field": 44, "near-field pulse": 28,
                                                    "near-field no pulse": 28}
    rec = record_by_key("fema-farfield:12:a")
    assert rec.component == "a" and rec.metadata["event"] == "Landers" and rec.metadata["year"] == 1992
    assert rec.metadata["pulse"] is None and load_suite_record("fema-nearfield:3:b").metadata["pulse"] is True
    # the recorded motion, not FEMA P695's normalised one: its PGA is the record's own
    assert rec.pga_g == pytest.approx(0.2828, abs=1e-4)


@pytest.mark.parametrize("key, words", [("fema-farfield:23:a", "allowed [1, 22]"),
                                        ("fema-nearfield:0:b", "allowed [1, 28]"),
                                        ("fema-farfield:1:c", "component a or b"),
                                        ("fema-nowhere:1:a", "suite one of farfield, nearfield"),
                                        ("fema-farfield:x:a", "fema-<suite>:<record id>:<component>")])
def test_unknown_or_out_of_range_keys_are_refused_naming_the_key(key, words):
    with pytest.raises(RecordError) as err:
        parse_key(key)
    assert key in str(err.value) and words in str(err.value)


def test_sa_of_every_ground_motion_agrees_with_the_packages_stored_spectrum():
    """Within 2 %: the package's spectra are on a grid of 500 periods (about 1.4 % apart), interpolated here."""
    worst = 0.0
    for key in ALL_KEYS:
        rec = load_suite_record(key)
        for period in PERIODS:
            worst = max(worst, abs(spectral_acceleration(rec, period) / stored_pseudo_acceleration(key, period) - 1))
    assert worst <= 0.02


def _exact_sdof_peak(record: Record, period: float, zeta: float) -> float:
    """An independent exact peak: lsim with first-order hold (exact for piecewise-linear input) at the samples, then
    inside the steps beside the largest samples on a sub-grid of h = dt / 20,000, whose largest value misses the
    true maximum by at most (omega h)^2 / 8 of it (about 5e-12 here)."""
    w = 2 * math.pi / period
    sys = signal.StateSpace([[0, 1], [-w * w, -2 * zeta * w]], [[0], [-1]], [[1, 0]], [[0]])
    a = record.accel_g * G_GRAV
    t = np.arange(len(a)) * record.dt
    _, u, x = signal.lsim(sys, a, t, interp=True)
    s = np.linspace(0.0, record.dt, 20001)
    best = 0.0
    for k in np.argsort(-np.abs(u))[:4]:
        for j in (k - 1, k):
            if 0 <= j < len(a) - 1:
                _, uu, _ = signal.lsim(sys, np.interp(s, [0, record.dt], a[j:j + 2]), s, X0=x[j], interp=True)
                best = max(best, float(np.max(np.abs(uu))))
    return w * w * best / G_GRAV


@pytest.mark.parametrize("key", SAMPLE_KEYS)
def test_sa_is_the_exact_peak_of_the_oscillator_between_samples(key):
    rec = load_suite_record(key)
    for period in PERIODS:
        assert spectral_acceleration(rec, period) == pytest.approx(_exact_sdof_peak(rec, period, 0.05), rel=1e-10)


@pytest.mark.parametrize("period", [0.0, -1.0, math.nan, 1e3])
def test_a_period_that_leaves_sa_undefined_is_refused_by_name(period):
    with pytest.raises(ParameterError, match="period_s"):
        spectral_acceleration(load_suite_record(SAMPLE_KEYS[0]), period)


def test_a_record_of_zeros_has_no_intensity_to_scale_to():
    with pytest.raises(ParameterError, match="zero at every sample"):
        spectral_acceleration(Record("flat", 0.01, np.zeros(50)), 1.0)


@pytest.mark.parametrize("key", SAMPLE_KEYS)
def test_an_untouchable_gap_gives_the_linear_building_under_each_suite(key):
    """The stage's 3-storey building with a CID it never reaches, against lsim (first-order hold) at the samples."""
    building = buildings.make_building(LOADS, "s3_T1")
    rec = load_suite_record(key)
    gm = IR.scaled_motion(rec, spectral_acceleration(rec, building.period1), 0.5)
    t, ref = _linear_roof(building, gm.accel, gm.dt)
    damper = buildings.impact_damper("cid", building, 0.02, gap=1e6, e=0.25)
    res = simulate_scene(Scene(building, (damper,), gm), times=t)
    assert res.impacts == 0
    assert np.max(np.abs(res.samples["q"][:, 2] - ref)) <= 1e-9 * np.max(np.abs(ref))


@pytest.mark.parametrize("kind", ["bare", "tmd"])
def test_the_bare_building_and_the_tmd_scale_exactly_with_the_level(kind):
    building = buildings.make_building(LOADS, "s3_T1")
    dampers = () if kind == "bare" else (tuned_for(building, 0.02),)
    rec = load_suite_record(SAMPLE_KEYS[3])
    sa = spectral_acceleration(rec, building.period1)
    levels = [0.05, 0.7, 1.5]
    scaled = IR.over_ladder(lambda lv: IR.measure(building, dampers, IR.scaled_motion(rec, sa, lv), 3.0), levels,
                            linear=True)
    direct = IR.over_ladder(lambda lv: IR.measure(building, dampers, IR.scaled_motion(rec, sa, lv), 3.0), levels,
                            linear=False)
    for name in IP.SCALED:
        np.testing.assert_allclose(scaled[name], direct[name], rtol=1e-12, equal_nan=True)
    assert np.all(np.abs(direct["energy_residual"]) <= 1e-9)


def test_a_tmd_with_stops_scales_where_they_are_out_of_reach_and_runs_where_they_are_struck():
    """Stops at the scaled stroke of the middle level: the levels below it are the free TMD's 1 g run scaled, the
    others are run with the stops and strike them; every level as a direct run with the stops gives."""
    building = buildings.make_building(LOADS, "s3_T1")
    rec = load_suite_record(SAMPLE_KEYS[3])
    sa = spectral_acceleration(rec, building.period1)
    levels = [0.05, 0.3, 0.7, 1.5]
    run_with = lambda dampers, lv: IR.measure(building, dampers, IR.scaled_motion(rec, sa, lv), 3.0)  # noqa: E731
    free_stroke = run_with((tuned_for(building, 0.02),), 1.0)["stroke"]
    stopped = replace(tuned_for(building, 0.02), stroke_limit=0.5 * free_stroke, e=0.25)
    ladder = IR.ladder_of(building, (stopped,), run_with, levels)
    direct = IR.over_ladder(lambda lv: run_with((stopped,), lv), levels, linear=False)
    assert list(direct["impacts"] > 0) == [False, False, True, True]
    assert np.all(direct["stroke"] <= stopped.stroke_limit * (1 + 1e-9))
    for name in IP.MEASURES:
        np.testing.assert_allclose(ladder[name], direct[name], rtol=1e-12, atol=1e-14 if name == "energy_residual"
                                   else 0, equal_nan=True, err_msg=name)
    assert np.all(np.abs(direct["energy_residual"]) <= 1e-9)


def test_the_designs_keep_their_strokes_within_the_limit():
    """A TMD's stops sit at the limit; an impact damper's clearance is twice it at most, and its design below."""
    building = buildings.make_building(LOADS, "s3_T1")
    tmd = IR.designed_damper(LOADS, IDA, building, "tmd", 0.02, {}, 0.3)
    assert (tmd.stroke_limit, tmd.e, tmd.tuning) == (1.0, LOADS["e"], tuned_for(building, 0.02).tuning)
    assert IR.designed_damper(LOADS, IDA, building, "cid", 0.02, {0.02: 4.0}, 0.6).gap == 2.0   # 2.4 designed
    assert IR.designed_damper(LOADS, IDA, building, "pid", 0.02, {0.02: 4.0}, 0.3).gap == pytest.approx(1.2)
    unlimited = {**IDA, "stroke_limit_m": None}
    assert IR.designed_damper(LOADS, unlimited, building, "tmd", 0.02, {}, 0.3).stroke_limit is None
    assert IR.designed_damper(LOADS, unlimited, building, "cid", 0.02, {0.02: 4.0}, 1.0).gap == 4.0


@pytest.fixture(scope="module")
def study():
    bare = {b: IR.bare_runs(IDA, LOADS, b) for b in IP.stage_buildings(LOADS)}
    dampers = {(b, k): IR.damper_runs(IDA, LOADS, b, k, bare[b], {} if k == "tmd" else {0.02: 1.0})
               for b in bare for k in ("cid", "pid", "tmd")}
    return bare, dampers, IT.collect(bare, dampers)


def test_an_impact_damper_that_never_reaches_its_walls_has_the_bare_buildings_ida_curve():
    bare = IR.bare_runs(IDA, LOADS, "s3_T1")
    far = IR.damper_runs(IDA, LOADS, "s3_T1", "cid", bare, {0.02: 1e4})
    assert float(far["impacts"].max()) == 0
    np.testing.assert_allclose(far["drift_ratio"].isel(mass_ratio=0), bare["drift_ratio"], rtol=1e-12)


def test_the_clearance_is_the_design_gap_ratio_times_the_median_bare_peak_at_the_design_level(study):
    bare, dampers, _ = study
    b = bare["s3_T1"]
    peak = float(np.median(b["peak_roof"].sel(level=IDA["design_sa_g"]).values))
    assert float(dampers["s3_T1", "cid"]["gap"].sel(mass_ratio=0.02)) == pytest.approx(peak, rel=1e-15)
    # each motion is scaled to its level: the oscillator of the building's period reads it back
    rec = load_suite_record(IDA["motions"][0])
    gm = IR.scaled_motion(rec, float(b["sa_record"].sel(motion=IDA["motions"][0])), 0.4)
    assert spectral_acceleration(Record("s", gm.dt, gm.accel / G_GRAV), 1.0) == pytest.approx(0.4, rel=1e-12)


def test_collected_drift_over_bare_is_the_runs_ratio_and_impact_dampers_strike(study):
    bare, dampers, ds = study
    cid = dampers["s1_T1", "cid"]["drift_ratio"].isel(mass_ratio=0)
    np.testing.assert_array_equal(ds["drift_over_bare"].sel(building="s1_T1", damper="cid", mass_ratio=0.02),
                                  cid / bare["s1_T1"]["drift_ratio"])
    # gap sized at the design level (0.4 g): there every run strikes
    assert float(ds["impacts"].sel(damper="cid", level=0.4).min()) > 0
    # and a run that never strikes (its mass's stroke within half the gap) is the bare building's, to round-off
    for kind in ("cid", "pid"):
        d = dampers["s3_T1", kind].isel(mass_ratio=0)
        quiet = d["impacts"].values == 0
        assert quiet.any() or kind == "pid"
        assert np.all(d["stroke"].values[quiet] <= 0.5 * float(d["gap"]))
        np.testing.assert_allclose(d["drift_ratio"].values[quiet], bare["s3_T1"]["drift_ratio"].values[quiet],
                                   rtol=1e-12)
    assert float(np.abs(ds["energy_residual"]).max()) <= 1e-9
    assert list(ds["group"].values) == ["far-field", "near-field pulse"]


def test_verdicts_count_helped_and_harmed_motions_and_bracket_the_median(study):
    *_, ds = study
    table = IT.verdicts(ds, IDA, 0.4)
    assert len(table) == 2 * 3 * 1 * 2   # buildings x dampers x mass ratios x groups present
    for _, row in table.iterrows():
        r = ds["drift_over_bare"].sel(building=row.building, damper=row.damper, mass_ratio=row.mass_ratio,
                                      level=0.4).values[ds["group"].values == row.group]
        assert row.median_reduction == pytest.approx(float(np.median(1 - r)))
        assert row.reduction_low <= row.median_reduction <= row.reduction_high
        assert row.share_lowered == float(np.mean(r <= 0.9)) and row.share_raised == float(np.mean(r > 1.05))
        stroke = ds["stroke"].sel(building=row.building, damper=row.damper, mass_ratio=row.mass_ratio,
                                  level=0.4).values[ds["group"].values == row.group]
        assert row.median_stroke_m == float(np.median(stroke)) <= IDA["stroke_limit_m"] * (1 + 1e-9)
    # a limit below every stroke counts every run at it; the 1 m limit, on these 1 s buildings at 0.4 g, none
    tight = IT.verdicts(ds, {**IDA, "stroke_limit_m": 1e-6}, 0.4)
    assert set(tight.share_at_stroke_limit) == {1.0}
    assert set(table.share_at_stroke_limit) == {0.0}


def test_the_collected_runs_share_one_configuration_but_the_designs_keys_bare_runs_lack():
    def run(**ida):
        params = {"study": {"ida": {"storey_height_m": 3.0, **ida}, "loads": {"e": 0.25}}}  # job_log.job_config's
        return xr.Dataset(attrs={"config": json.dumps(params, sort_keys=True)})

    damped = run(storey_height_m=3.0, design_sa_g=0.4, stroke_limit_m=1.0)
    assert IT.run_config({"s1": run()}, {("s1", "cid"): damped}) == damped.attrs["config"]
    for bare, other in ((run(storey_height_m=4.0), damped), (run(), run(design_sa_g=0.4, stroke_limit_m=2.0))):
        with pytest.raises(ValueError, match="different configurations"):
            IT.run_config({"s1": run(), "s3": bare}, {("s1", "cid"): damped, ("s1", "tmd"): other})


def test_the_bootstrap_resamples_whole_records():
    # two records of two components each: a record-level resample can only give medians of whole records' values
    values = np.array([0.0, 0.0, 1.0, 1.0])
    lo, hi = IT.bootstrap_median(values, np.array(["r1", "r1", "r2", "r2"]), 500, 3, 0.9)
    assert (lo, hi) == (0.0, 1.0)


def test_the_lognormal_fit_recovers_a_known_fragility():
    theta, beta = 0.6, 0.45
    levels = np.array([0.1, 0.2, 0.3, 0.45, 0.6, 0.8, 1.0, 1.3, 1.7])
    total = np.full(len(levels), 100000.0)
    exceed = np.round(total * 0.5 * (1 + np.vectorize(math.erf)(np.log(levels / theta) / (beta * math.sqrt(2)))))
    fit = IT.lognormal_fit(levels, exceed, total)
    assert fit == pytest.approx((theta, beta), rel=1e-3)
    assert all(math.isnan(v) for v in IT.lognormal_fit(levels, np.zeros(len(levels)), total))


@pytest.mark.parametrize("change, words", [
    ({"sa_g": []}, "ida.sa_g is empty"),
    ({"sa_g": [0.4, 0.1]}, "must rise strictly"),
    ({"design_sa_g": 0.3}, "ida.design_sa_g = 0.3 must be one of"),
    ({"motions": ["fema-farfield:23:a"]}, "ida.motions: record key 'fema-farfield:23:a'"),
    ({"motions": ["elcentro"]}, "ida.motions: 'elcentro' is not a FEMA P695 key"),
])
def test_bad_ida_config_names_the_key(change, words):
    with pytest.raises(ParameterError) as err:
        IP.check_config({**IDA, **change}, LOADS)
    assert words in str(err.value)
    with pytest.raises(ParameterError, match="needs the loads section"):
        IP.check_config(IDA, None)


def test_a_single_storey_building_of_the_period_asked_is_the_oscillator_sa_reads():
    """Sa is read on the building's own first-mode period: a one-storey building at 5 % is the oscillator itself."""
    rec = load_suite_record(SAMPLE_KEYS[0])
    res = simulate_scene(Scene(Building.uniform(1, 1.0, 0.05), (), GroundMotion.from_record(rec)))
    assert spectral_acceleration(rec, 1.0) == pytest.approx((2 * math.pi) ** 2 * res.peak_roof_displacement / G_GRAV,
                                                            rel=1e-15)


def test_cli_lists_the_suites_and_runs_a_building_under_one_of_their_ground_motions(capsys):
    import json

    from impact.cli import main

    main(["records", "--suite", "nearfield"])
    rows = json.loads(capsys.readouterr().out)["nearfield"]
    assert len(rows) == 56 and rows[0]["key"] == "fema-nearfield:1:a" and rows[0]["group"] == "near-field pulse"
    main(["quake", "--record", "fema-farfield:12:a", "--storeys", "3", "--pga-g", "0.3", "--duration-s", "5"])
    out = json.loads(capsys.readouterr().out)
    assert out["record"]["metadata"]["event"] == "Landers" and out["record"]["pga_g"] == pytest.approx(0.3)
    assert out["peak_roof_displacement_m"] > 0
    for key, words in (("fema-farfield:23:a", "allowed [1, 22]"), ("fema-farfield:1", "fema-<suite>")):
        with pytest.raises(SystemExit) as exc:
            main(["quake", "--record", key])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and key in err and words in err
