"""The earthquake and wind study (impact.stages.loads): exact limits, linearity, seeds and the tables' logic."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from test_scene import _linear_roof

from impact.engine.scenes import simulate_scene
from impact.model.params import ParameterError
from impact.model.records import load_record
from impact.model.scene import DAMPER_KINDS, GroundMotion, Scene
from impact.stages import buildings
from impact.stages.loads import plan as LP
from impact.stages.loads import runs as LR
from impact.stages.loads import tables as LT

CFG = {
    "storeys": [1, 3], "periods_s": [0.5], "zeta": 0.02, "mass_ratios": [0.02], "e": 0.25, "gap_ratios": [0.5, 1.0],
    "records": {"names": ["northridge"], "pga_g": [0.1, 0.35], "design_pga_g": 0.35},
    "kanai_tajimi": {"seeds": 2, "soils": ["firm"], "duration_s": 8.0, "dt_s": 0.01, "rise_s": 1.0,
                     "plateau_end_s": 5.0, "decay_per_s": 0.5},
    "wind": {"buildings": ["s3_T0.5"], "seeds": 1, "duration_periods": 60, "dt_periods": 0.05, "bandwidth": 0.1,
             "rms_weight_share": 0.005},
    "time_history": {"building": "s3_T0.5", "record": "northridge", "damper": "cid", "mass_ratio": 0.02},
}


@pytest.fixture(scope="module")
def study():
    bare = {b: LR.bare_runs(CFG, b) for b in buildings.buildings(CFG)}
    dampers = {(b, k): LR.damper_runs(CFG, b, k, bare[b]) for b in bare for k in DAMPER_KINDS}
    return bare, dampers, LT.collect(bare, dampers)


def test_untouchable_gap_gives_the_bare_building_under_el_centro_to_1e_9():
    """The stage's five-storey building with a CID it never touches, against lsim of the linear building."""
    building = buildings.make_building({**CFG, "storeys": [5], "periods_s": [2.0]}, "s5_T2")
    gm = GroundMotion.from_record(load_record("elcentro"), pga_g=0.35)
    t, ref = _linear_roof(building, gm.accel, gm.dt)
    damper = buildings.impact_damper("cid", building, 0.02, gap=1e6, e=0.25)
    res = simulate_scene(Scene(building, (damper,), gm), times=t)
    assert res.impacts == 0
    assert np.max(np.abs(res.samples["q"][:, 4] - ref)) <= 1e-9 * np.max(np.abs(ref))
    bare = LR.run(building, (), LP.Load("records", {"record": "elcentro", "intensity": 0.35}, gm))
    assert bare["peak_roof"] == pytest.approx(res.peak_roof_displacement, rel=1e-12)
    assert bare["peak_roof"] >= np.max(np.abs(ref)) * (1 - 1e-12)


def test_each_seed_is_deterministic_and_scaled_to_its_pga():
    first, again = LP.random_loads(CFG), LP.random_loads(CFG)
    for a, b in zip(first, again):
        assert a.labels == b.labels
        np.testing.assert_array_equal(a.load.accel, b.load.accel)
        assert a.load.pga == pytest.approx(a.labels["intensity"] * 9.80665, rel=1e-12)
    seeds = {ld.labels["seed"]: ld.load.accel for ld in first if ld.labels["intensity"] == 0.1}
    assert not np.allclose(seeds[0], seeds[1])
    w1, w2 = (LP.wind_loads(CFG, buildings.make_building(CFG, "s3_T0.5"))[0].load.values for _ in range(2))
    np.testing.assert_array_equal(w1, w2)


def test_linear_systems_scale_with_the_pga(study):
    """The bare building and the TMD are linear: responses scale with the PGA, ratios do not move (1e-9)."""
    bare, dampers, _ = study
    for b, ds in bare.items():
        peak = ds["records_peak_roof"].sel(record="northridge")
        assert float(peak.sel(intensity=0.35) / peak.sel(intensity=0.1)) == pytest.approx(3.5, rel=1e-9)
        ratio = dampers[b, "tmd"]["kanai_tajimi_peak_roof_ratio"]
        spread = ratio.max("intensity") - ratio.min("intensity")
        assert float(spread.max()) <= 1e-9


def test_impact_dampers_stay_within_their_gap_and_the_gap_is_sized_at_the_design_level(study):
    bare, dampers, _ = study
    for (b, kind), ds in dampers.items():
        if kind == "tmd":
            continue
        design = float(bare[b]["records_peak_roof"].sel(record="northridge", intensity=0.35))
        g = ds["records_design_gap_ratio"].values
        assert set(g) <= set(CFG["gap_ratios"])
        half_gap = 0.5 * g[:, None, None] * design
        assert np.all(ds["records_stroke"].values <= half_gap * (1 + 1e-9))
        assert np.all(ds["records_impacts"].values > 0)
        # the design gap is the best of the swept ones, by the mean peak roof ratio over the records
        swept = ds["records_peak_roof_ratio_vs_gap"].mean(["record", "intensity"])
        assert float(swept.idxmin("gap_ratio").item()) == float(g[0])


def test_the_best_damper_is_the_lowest_ratio_and_verdicts_count_every_run(study):
    _, _, out = study
    best = LT.best_damper_table(out)
    ratios = best[[f"{k}_peak_roof_ratio" for k in DAMPER_KINDS]].to_numpy()
    chosen = best["best"].map(lambda k: DAMPER_KINDS.index(k)).to_numpy()
    np.testing.assert_array_equal(chosen, np.nanargmin(ratios, axis=1))
    verdicts = LT.verdict_table(out)
    assert (verdicts["helps"] + verdicts["does_nothing"] + verdicts["makes_worse"] == verdicts["cases"]).all()
    records = verdicts[(verdicts["load"] == "records") & (verdicts["measure"] == "peak_roof")]
    assert set(records["cases"]) == {len(buildings.buildings(CFG)) * 2}   # buildings x PGAs x one record
    assert set(verdicts["load"]) == {"records", "kanai-tajimi firm", "wind"}


def test_collected_ratios_are_the_runs_over_the_bare_runs(study):
    bare, dampers, out = study
    ds = out["records"]
    for (b, kind), d in dampers.items():
        np.testing.assert_array_equal(ds["peak_roof"].sel(building=b, damper=kind).values,
                                      d["records_peak_roof"].values)
        np.testing.assert_allclose(ds["peak_roof_ratio"].sel(building=b, damper=kind).values,
                                   (d["records_peak_roof"] / bare[b]["records_peak_roof"]).values, rtol=1e-15)


def test_bad_loads_config_names_the_key():
    bad = copy.deepcopy(CFG)
    bad["records"]["design_pga_g"] = 0.2
    with pytest.raises(ParameterError, match="loads.records.design_pga_g"):
        LP.check_config(bad)
    bad = copy.deepcopy(CFG)
    bad["wind"]["buildings"] = ["s9_T3"]
    with pytest.raises(ParameterError, match="loads.wind.buildings"):
        LP.check_config(bad)


#: a building of the user's own, floor by floor: a heavy soft first storey under a lighter stiffer second one
FRAME_A = {"masses_kg": [2.0e5, 1.5e5], "storey_stiffness_n_per_m": [6.0e7, 3.0e7]}


def test_a_building_given_floor_by_floor_is_a_building_of_the_stage():
    """What a new user missed: their own non-uniform building in the pipeline's configuration.  It is made as
    impact quake --masses-kg makes it, beside the uniform ones, and the wind and the time history may load it."""
    from impact.model.building import Building

    cfg = {**copy.deepcopy(CFG), "buildings": {"frame-a": FRAME_A}}
    cfg["wind"]["buildings"] = ["frame-a"]
    cfg["time_history"]["building"] = "frame-a"
    LP.check_config(cfg)
    assert list(buildings.buildings(cfg)) == ["s1_T0.5", "s3_T0.5", "frame-a"]
    made = buildings.make_building(cfg, "frame-a")
    same = Building.explicit(FRAME_A["masses_kg"], FRAME_A["storey_stiffness_n_per_m"], zeta=CFG["zeta"])
    for field in ("masses", "storey_stiffness", "damping"):
        np.testing.assert_array_equal(getattr(made, field), getattr(same, field))
    # a stage's slice of the section carries it; without it, the slice is what it was (no other job reruns)
    assert buildings.shared_keys(cfg)["buildings"] == {"frame-a": FRAME_A}
    assert "buildings" not in buildings.shared_keys(CFG)


@pytest.mark.parametrize("change, words", [
    ({"buildings": {"frame-a": {**FRAME_A, "masses_kg": [2.0e5]}}}, r"loads.buildings.frame-a: storey_stiffness"),
    ({"buildings": {"frame-a": {**FRAME_A, "masses_kg": [2.0e5, -1.0]}}}, r"loads.buildings.frame-a: masses"),
    ({"storeys": [], "periods_s": []}, r"loads: no building"),
])
def test_a_building_that_cannot_be_made_is_refused_naming_its_key(change, words):
    with pytest.raises(ParameterError, match=words):
        LP.check_config({**copy.deepcopy(CFG), **change})
