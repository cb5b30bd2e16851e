"""Table 1 in numbers (impact.stages.robustness): the measures against exact similarities and linearity."""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from impact.engine.run import sweep
from impact.model.params import Protocol, System
from impact.stages.robustness.designs import Conditions, Design, designs_from_study, stroke_cap
from impact.stages.robustness.runs import design_dataset, multi_unit, peak_response, scene_peak_response
from impact.stages.robustness.table import same_level, table1_measured, within_band

BETA = 0.0048
SHORT = Protocol(periods=120, average_from=60)
R = np.array([0.97, 0.99, 1.0, 1.01, 1.03])


def test_tmd_amplitude_sensitivity_is_flat():
    """A TMD is linear: X_m is the same at a tenth and at ten times the design force."""
    tmd = Design("tmd", 0.01, BETA, tuning=0.989, damping=0.062)
    xm = [peak_response(tmd, R, SHORT, Conditions(scale=s))["X_m"] for s in (0.1, 1.0, 10.0)]
    assert max(xm) - min(xm) <= 1e-9 * xm[1]


def test_cid_amplitude_sensitivity_is_not_flat():
    cid = Design("cid", 0.01, BETA, gap_ratio=1.6, start="left")
    xm = [peak_response(cid, R, SHORT, Conditions(scale=s))["X_m"] for s in (0.5, 1.0, 2.0)]
    assert max(xm) / min(xm) > 1.2


@pytest.mark.parametrize("kind, tuning", [("cid", 1.0), ("pid", 1.0)])
@pytest.mark.parametrize("delta", [-0.1, 0.1])
def test_a_drifted_structure_is_the_design_in_its_own_time(kind, tuning, delta):
    """The paper kernel's similar system (force over (1 + delta)^2, pendulum frequency over 1 + delta) against
    the drifted building run directly on the scene core.  At r = 1 the runs settle on a periodic motion;
    on chaotic ones the two kernels' round-offs would part."""
    design = Design(kind, 0.01, BETA, gap_ratio=1.4, tuning=tuning, start="left")
    r = np.array([1.0])
    similar = peak_response(design, r, SHORT, Conditions(drift=delta))
    direct = scene_peak_response(design, r, SHORT, Conditions(drift=delta))
    assert similar["X_m"] == pytest.approx(direct["X_m"], rel=1e-9)
    assert similar["X_m"] != pytest.approx(peak_response(design, r, SHORT)["X_m"], rel=1e-3)


def test_the_gap_as_designed_is_a_cid_at_another_gap_ratio():
    """Drift delta of a CID is the design with g (1 + delta)^2 (the CID has no tuning to lose); lengths are
    scaled by (1 + delta)^2, so the two agree to round-off where the run is periodic (r = 1)."""
    g, delta, r = 1.4, 0.1, np.array([1.0])
    drifted = peak_response(Design("cid", 0.01, BETA, gap_ratio=g, start="left"), r, SHORT, Conditions(drift=delta))
    same = System.from_gap_ratio("cid", 0.01, BETA, 0.25, g * (1 + delta) ** 2)
    runs = sweep(same, r, Protocol(periods=SHORT.periods, average_from=SHORT.average_from, start="left")).runs
    assert drifted["X_m"] == pytest.approx(runs[0].amplitude_ratio, rel=1e-9)


def test_a_tmd_left_as_designed_loses_its_tuning():
    tmd = Design("tmd", 0.01, BETA, tuning=0.989, damping=0.062)
    protocol = Protocol(periods=300, average_from=150)
    grid = np.linspace(0.9, 1.1, 21)
    design = peak_response(tmd, grid, protocol)["X_m"]
    assert peak_response(tmd, grid, protocol, Conditions(drift=-0.1))["X_m"] > 2 * design


@pytest.mark.parametrize("x, xm, expected", [
    ([0.5, 1.0, 2.0, 4.0], [0.9, 1.0, 1.2, 2.0], (0.5, 2.0)),
    ([0.5, 1.0, 2.0], [2.0, 1.0, 1.3], (1.0, 1.0)),
    ([-0.1, 0.0, 0.1], [1.0, 1.0, 1.0], (-0.1, 0.1)),
])
def test_within_band_is_the_contiguous_range_around_the_design(x, xm, expected):
    at = 0.0 if min(x) < 0 else 1.0
    assert within_band(x, xm, 1.0, at) == expected


def _fake(kind, xm, **changes):
    data = {"X_m_design": ((), xm), "stroke_max_design": ((), 5.0)}
    for name, values in changes.items():
        data[f"X_m_vs_{name}"] = (name, values)
    coords = {name: (name, np.linspace(0.5, 2.0, len(v))) for name, v in changes.items()}
    return xr.Dataset(data, coords=coords, attrs={"kind": kind, "a_max": 10.0})


def test_a_number_supports_its_word_when_it_orders_like_the_words():
    designs = {"cid": _fake("cid", 0.3, scale=[0.6, 0.3, 0.2]), "pid": _fake("pid", 0.5, scale=[0.55, 0.5, 0.4]),
               "tmd": _fake("tmd", 0.12, scale=[0.12, 0.12, 0.12])}
    table = table1_measured(designs).set_index(["row", "design"])
    # amplitude: CID high (1.0), PID moderate (0.2), TMD low (0): as the words order
    assert list(table.loc[9]["supports"]) == ["yes", "yes", "yes"]
    # effectiveness: TMD high with the smallest X_m; CID and PID moderate
    assert table.loc[(2, "tmd"), "supports"] == "yes"
    designs["pid"] = _fake("pid", 0.5, scale=[2.0, 0.5, 0.4])  # now more sensitive than the CID
    table = table1_measured(designs).set_index(["row", "design"])
    assert table.loc[(9, "cid"), "supports"] == "no" and table.loc[(9, "pid"), "supports"] == "no"
    assert table.loc[(7, "cid"), "supports"] == "not judged" and math.isnan(table.loc[(7, "cid"), "number"])


def test_designs_are_the_sweeps_optima():
    cfg = {"robustness": {"mu": 0.01, "e": 0.25, "pid_tunings": [0.5, 1.0]},
           "structure": {"beta": BETA, "force_ratio": 0.096},
           "protocol": {"starts": {"cid": ["centre", "left"], "pid": ["centre"]}}}
    optima = {"cid": {"centre": 1.4, "left": 1.6}, "rp0.5": {"centre": 1.4}, "rp1": {"centre": 4.6}}
    designs = designs_from_study(cfg, optima, {"f": 0.989, "beta_t": 0.062})
    assert list(designs) == ["cid_centre", "cid_left", "pid_rp0.5_centre", "pid_rp1_centre", "tmd"]
    assert designs["cid_left"]["gap_ratio"] == 1.6 and designs["pid_rp1_centre"]["tuning"] == 1.0
    assert designs["tmd"]["damping"] == 0.062
    assert stroke_cap(designs) == pytest.approx(0.5 * 1.4 * 10.0)


def test_design_dataset_holds_only_what_applies():
    grids = {"scale": [0.5, 1.0], "drift": [0.0], "damping": [0.05], "e": [0.5]}
    cid = design_dataset(Design("cid", 0.01, BETA, gap_ratio=1.6), grids, R[:2], SHORT)
    assert "X_m_vs_e" in cid and "X_m_vs_damping" not in cid
    tmd = design_dataset(Design("tmd", 0.01, BETA, tuning=0.989, damping=0.062), grids, R[:2], SHORT)
    assert "X_m_vs_e" not in tmd and "X_m_vs_damping" in tmd


def test_the_one_unit_row_is_the_single_damper():
    """n = 1 of the multi-unit rows is the single damper's X_m (scene core against the paper kernel), and
    identical units that start together move as one, so every n gives it too."""
    design = Design("cid", 0.01, BETA, gap_ratio=1.6, start="left")
    r = np.array([1.0])
    rows = multi_unit(design, [1, 2, 9], r, SHORT, members=1, seed=3)
    single = peak_response(design, r, SHORT)["X_m"]
    assert rows["symmetric"][0] == pytest.approx(single, rel=1e-9)
    assert rows["staggered"][0] == pytest.approx(single, rel=1e-9)
    assert rows["symmetric"] == pytest.approx([single] * 3, rel=1e-9)
    assert rows["staggered"][2] != pytest.approx(single, rel=1e-3)  # spread over the gap, they do not


def test_units_started_at_a_wall_are_the_protocols_wall_start():
    design = Design("pid", 0.01, BETA, gap_ratio=1.4, tuning=0.5, start="left")
    r = np.array([0.98, 1.02])
    wall = scene_peak_response(design, r, SHORT)
    placed = scene_peak_response(design, r, SHORT, unit_starts=[-0.5 * design.gap])
    assert placed == wall


def test_the_multi_unit_verdict_reads_each_start_against_its_own_single_unit():
    ds = xr.Dataset({"X_m_units_symmetric": ("units", [0.30, 0.30, 0.30]),
                     "X_m_units_staggered": ("units", [0.30, 0.31, 0.40]),
                     "X_m_units_ensemble": (("units", "member"), [[0.5, 0.3, 0.4], [0.4, 0.42, 0.41], [0.4, 0.4, 0.4]])},
                    coords={"units": [1, 2, 9]})
    change, holds = same_level(ds)
    assert change == pytest.approx(0.40 / 0.30 - 1) and not holds
    ds["X_m_units_staggered"] = ("units", [0.30, 0.31, 0.32])
    change, holds = same_level(ds)
    assert change == pytest.approx(0.32 / 0.30 - 1) and holds


def test_the_multi_unit_verdict_is_withheld_where_a_run_failed():
    ds = xr.Dataset({"X_m_units_symmetric": ("units", [0.30, 0.30]),
                     "X_m_units_staggered": ("units", [0.30, np.nan]),
                     "X_m_units_ensemble": (("units", "member"), [[0.3], [0.3]])}, coords={"units": [1, 9]})
    change, holds = same_level(ds)
    assert change == 0.0 and holds is None


def test_a_defined_change_beyond_the_band_refutes_the_claim_despite_a_failed_run():
    """'Up to 9 units give the same level' is a claim about every n: one defined counterexample refutes it."""
    ds = xr.Dataset({"X_m_units_symmetric": ("units", [0.30, 0.30, 0.30]),
                     "X_m_units_staggered": ("units", [0.30, 0.36, np.nan]),
                     "X_m_units_ensemble": (("units", "member"), [[0.3], [0.3], [np.nan]])},
                    coords={"units": [1, 2, 9]})
    change, holds = same_level(ds)
    assert change == pytest.approx(0.2) and holds is False
    from impact.stages.robustness.table import _multi_unit_row

    row = _multi_unit_row("cid_left", ds.assign_attrs(kind="cid"))
    assert row["supports"] == "no" and "n = 9" in row["note"] and "refutes" in row["note"]
