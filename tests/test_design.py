"""Design charts and `impact design` (impact.stages.design): the chart is the study's runs, and its answers hold."""

from __future__ import annotations

import json

import numpy as np
import pytest

from impact.cli import main
from impact.engine.run import sweep
from impact.model.params import Protocol, System, curve_id
from impact.outputs.files import write_dataset
from impact.stages.curves import curve_specs
from impact.stages.design import chart_config, chart_specs, impact_chart, tmd_chart, tmd_mu_grid
from impact.stages.robustness.designs import design_curves
from impact.stages.sweeps import freq_grid, run_curve

CFG = {
    "structure": {"beta": 0.0048, "force_ratio": 0.096},
    "protocol": {"periods": 100, "average_from": 50, "phase": 0.0, "freq": {"min": 0.9, "max": 1.1, "step": 0.05},
                 "gap": {"min": 0.6, "max": 2.4, "step": 0.6}, "starts": {"cid": ["centre", "left"],
                                                                          "pid": ["centre"]}},
    "design": {"mu": [0.01, 0.03], "e": [0.25, 0.65], "pid_tunings": [1.0], "tmd_points": 3,
               "freq": {"min": 0.96, "max": 1.04, "step": 0.02}},
}


@pytest.fixture(scope="module")
def sweeps():
    cfg = chart_config(CFG)
    return {kind: [run_curve(cfg, spec) for spec in chart_specs(CFG["design"], kind)] for kind in ("cid", "pid")}


@pytest.fixture(scope="module")
def chart_dir(sweeps, tmp_path_factory):
    """The three charts of the small study above, written as the pipeline writes them."""
    out = tmp_path_factory.mktemp("charts")
    for kind, runs in sweeps.items():
        write_dataset(impact_chart(kind, runs), out / f"chart_{kind}.nc")
    s = CFG["structure"]
    write_dataset(tmd_chart(tmd_mu_grid(CFG["design"]), s["beta"], s["force_ratio"], CFG["protocol"],
                            freq_grid(chart_config(CFG))), out / "chart_tmd.nc")
    return out


def _design_json(capsys, *argv):
    assert main(["design", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_charts_and_the_robustness_designs_plan_their_curves_one_way():
    """A kind with a spring gets a curve per tuning, one without gets one; the charts' and the robustness
    designs' curves are distinct files."""
    design = {"mu": [0.01, 0.02], "e": [0.25, 0.65], "pid_tunings": [0.5, 1.0]}
    cid, pid = chart_specs(design, "cid"), chart_specs(design, "pid")
    assert len(cid) == 4 and len(pid) == 8 and all("rp" not in s for s in cid) and {s["rp"] for s in pid} == {0.5, 1.0}
    assert len({curve_id(s) for s in cid + pid}) == 12
    robust = design_curves({"robustness": {"mu": 0.01, "e": 0.25, "pid_tunings": [1.0, 1.5]}})
    assert [curve_id(s) for s in robust] == ["cid_mu0.01_e0.25", "pid_mu0.01_e0.25_rp1", "pid_mu0.01_e0.25_rp1.5"]
    assert robust == curve_specs(("cid", "pid"), [0.01], [0.25], [1.0, 1.5])


def test_a_chart_is_each_runs_refined_peak_the_worst_over_starts(sweeps):
    chart = impact_chart("cid", sweeps["cid"])
    for ds in sweeps["cid"]:
        spec = json.loads(ds.attrs["curve"])
        at = chart.sel(e=spec["e"], mu=spec["mu"])
        np.testing.assert_array_equal(at["X_m"].values, ds["X_m_refined"].max("start").values)
        best = int(np.argmin(ds["X_m_refined"].max("start").values))
        assert float(at["gap_ratio_best"]) == ds["gap_ratio"].values[best]
    assert set(chart["start"].values) == {"centre", "left"}
    assert np.all(chart["X_m"] >= chart["X_m_start"])
    assert "forced at r = 0.96 to 1.04" in chart.attrs["design_point"]


def test_design_read_off_a_chart_meets_the_target_by_direct_simulation(chart_dir, capsys):
    """A target read off the chart (a design's X_m, plus a little) is met by the answer's own simulation,
    and the answer's flags, pasted into `impact sweep`, give the same numbers."""
    import xarray as xr

    chart = xr.load_dataset(chart_dir / "chart_cid.nc")
    target = float(chart["X_m_best"].sel(e=0.25, mu=0.03)) + 0.01
    answer = _design_json(capsys, "--target-xm", str(target), "--damper", "cid", "--charts", str(chart_dir))
    assert answer["damper"] == "cid" and answer["mu"] <= 0.03
    assert answer["xm_chart"] <= target and answer["xm_simulated"] <= target
    assert {"mu", "gap_ratio", "e", "xm_chart", "xm_simulated"} <= set(answer)
    step = chart.attrs["freq_step"] / 5
    per_start = []
    for start in answer["starts"]:
        assert main(["sweep", "--damper", "cid", "--mu", str(answer["mu"]), "--e", str(answer["e"]),
                     "--gap-ratio", str(answer["gap_ratio"]), "--start", start, "--periods", "100",
                     "--average-from", "50", "--r-min", str(answer["r_min"]), "--r-max", str(answer["r_max"]),
                     "--r-step", str(step)]) == 0
        per_start.append(json.loads(capsys.readouterr().out)["X_m"])
    assert max(per_start) == pytest.approx(answer["xm_simulated"], rel=1e-12)
    # without --json: the same design as text, with the sweep that reruns it
    assert main(["design", "--target-xm", str(target), "--damper", "cid", "--charts", str(chart_dir)]) == 0
    text = capsys.readouterr().out
    assert f"--mu {answer['mu']} --e {answer['e']} --gap-ratio {answer['gap_ratio']}" in text
    assert f"{answer['xm_simulated']:.4f} simulated" in text


def test_pid_and_tmd_answers_carry_their_tuning(chart_dir, capsys):
    pid = _design_json(capsys, "--target-xm", "1.0", "--damper", "pid", "--charts", str(chart_dir))
    assert pid["rp"] == 1.0 and pid["xm_simulated"] <= 1.0
    tmd = _design_json(capsys, "--target-xm", "0.2", "--damper", "tmd", "--charts", str(chart_dir))
    assert tmd["mu"] == 0.01 and tmd["gap_ratio"] is None
    # the TMD's chart is its closed-form true peak; the scene core's run at the peaks agrees
    assert tmd["xm_simulated"] == pytest.approx(tmd["xm_chart"], rel=2e-3)


def test_an_unreachable_target_is_refused_with_the_best_reachable_xm(chart_dir, capsys):
    import xarray as xr

    best = float(xr.load_dataset(chart_dir / "chart_cid.nc")["X_m"].min())
    with pytest.raises(SystemExit) as exc:
        main(["design", "--target-xm", "0.001", "--damper", "cid", "--charts", str(chart_dir), "--json"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "not reachable" in err and f"best reachable X_m is {best:.4g}" in err


def test_force_scaled_with_the_gap_fixed_is_the_chart_at_g_over_s():
    """The similarity --amplitude-range reads the charts by: X_m(s F, d) = X_m(F, d / s) for every start."""
    grid = np.array([0.97, 1.0, 1.02])
    for start in ("centre", "left"):
        proto = Protocol(periods=100, average_from=50, start=start)
        base = System.from_gap_ratio("cid", mu=0.02, beta=0.0048, e=0.45, gap_ratio=1.2, force_ratio=0.096)
        for s in (0.5, 2.0):
            scaled = System("cid", mu=0.02, beta=0.0048, e=0.45, gap=base.gap, force_ratio=0.096 * s)
            similar = System.from_gap_ratio("cid", mu=0.02, beta=0.0048, e=0.45, gap_ratio=1.2 / s,
                                            force_ratio=0.096)
            a = sweep(scaled, grid, proto).x_max / scaled.a_max
            b = sweep(similar, grid, proto).x_max / similar.a_max
            assert a == pytest.approx(b, rel=1e-9)


def test_amplitude_range_answers_hold_over_the_range(chart_dir, capsys):
    wide = _design_json(capsys, "--target-xm", "1.0", "--damper", "cid", "--charts", str(chart_dir),
                        "--amplitude-range", "0.5", "2")
    assert wide["xm_chart_range"] >= wide["xm_chart"]
    assert wide["xm_simulated_range"] <= 1.0 and 0.5 <= wide["worst_scale"] <= 2.0
    with pytest.raises(SystemExit):
        main(["design", "--target-xm", "1.0", "--damper", "cid", "--charts", str(chart_dir),
              "--amplitude-range", "2", "3"])
