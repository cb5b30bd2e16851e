"""Why the PID has no design equation (docs/design-equations.md, "The soft pendulum on a fine grid"): the fine
scans that docs/pid_gap_scan.json holds are the engine's, the summary the docs quote is the tool's fit of them,
and the docs quote it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from impact.stages.design.equations.formulas import Point, direct_xm

ROOT = Path(__file__).resolve().parents[1]
TOOL = ROOT / "tools" / "pid_gap_scan.py"
SCAN = json.loads((ROOT / "docs" / "pid_gap_scan.json").read_text())
STUDY = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())


def test_the_summary_is_the_fit_of_the_stored_scans(tool):
    summary, _ = tool.summarise(SCAN["rows"], STUDY["design"]["equations"], SCAN["summary"]["soft_max_rp"])
    stored = {k: v for k, v in SCAN["summary"].items() if k != "seconds"}
    assert set(summary) == set(stored)
    for name, value in stored.items():
        assert summary[name] == (pytest.approx(value, rel=1e-6) if value is not None else None), name


def test_the_cliff_is_the_engines():
    """The largest cliff the scans found, simulated again: X_m at the optimum gap and one step (0.01) below it, the
    worst over the starts on the charts' window, as stored; and the step below is the other motion, several times
    higher."""
    worst = SCAN["summary"]["cliff_worst"]
    row = next(r for r in SCAN["rows"] if all(r[k] == worst[k] for k in ("mu", "e", "rp")))
    gaps = [round(row["gap"] - 0.01, 6), row["gap"]]
    again = direct_xm(STUDY, "pid", Point(row["mu"], row["e"], row["beta"], row["rp"]), gaps)
    stored = [row["fine_X_m"][row["fine_gaps"].index(g)] for g in gaps]
    np.testing.assert_allclose(again, stored, rtol=1e-5)
    assert again[0] / again[1] > 2.0


def _signed(x: float) -> str:
    return f"{x:+.1%}".replace("-", "−")


def quotes(s: dict) -> dict:
    """What docs/design-equations.md says of the scans, each as the summary renders it."""
    law, cliff, grid = s["gap_law"], s["cliff_worst"], s["grid_over_fine_worst"]
    k, band = s["branch_exponent"], s["band_above_optimum"]
    margin15 = ((1.0 + s["gap_error_fitted"][1]) * 1.15) ** k - 1.0  # the law's largest over-estimate, raised 15 %
    return {
        "CLIFF_SOFT": f"{s['soft_designs']}", "CLIFF_MAX": f"{s['cliff_max']:.1f}",
        "CLIFF_WHERE": f"r' = {cliff['rp']:g}, μ = {cliff['mu']:g}, e = {cliff['e']:g}: {cliff['X_m']:.3f} at "
                       f"g = {cliff['gap']:.2f}, {cliff['X_m'] * s['cliff_max']:.3f} at {cliff['gap'] - 0.01:.2f}",
        "BRANCH_K": f"{k:.2f}", "BAND": f"{band:.1%}", "BAND_SHORT": f"{band:.1%}", "HALF_BAND": f"{band / 2:.1%}",
        "GRID_OVER": f"{s['grid_over_fine_max']:.0%}",
        "GRID_WHERE": f"r' = {grid['rp']:g}, μ = {grid['mu']:g}, e = {grid['e']:g}: {grid['grid_X_m']:.3f} at "
                      f"g = {grid['grid_gap']:.1f} against {grid['X_m']:.3f} at {grid['gap']:.2f}",
        "LAW_P": f"{law['p']:.2f}", "LAW_W": f"{law['w']:.2f}",
        "ERR_FIT": f"{_signed(s['gap_error_fitted'][0])} to {_signed(s['gap_error_fitted'][1])}",
        "ERR_HELD": f"{_signed(s['gap_error_held_out'][0])} to {_signed(s['gap_error_held_out'][1])}",
        "WITHIN": f"{s['held_out_within_plateau']}", "HELD": f"{s['held_out']}",
        "BEYOND": f"{s['held_out_beyond_plateau']}", "OVER_MAX": f"{s['held_out_over_optimum_max']:.0%}",
        "EDGE": f"{s['held_out_at_or_below_edge']}", "MARGIN15": f"{margin15:.0%}",
        "STIFF_RANGE": "{:.2f} to {:.2f}".format(*s["best_X_m_stiffer"]),
        "SOFT_RANGE": "{:.2f} to {:.2f}".format(*s["best_X_m_soft"]),
    }


#: each quote in its sentence, so that a number the docs quote elsewhere cannot stand in for it
CONTEXT = {
    "CLIFF_SOFT": "of which {} soft designs", "CLIFF_MAX": "up to\n**{} times** higher", "CLIFF_WHERE": "({})",
    "BRANCH_K": "power **{}** of the gap", "BAND": "to **{}** above it", "BAND_SHORT": "is {} wide",
    "HALF_BAND": "edge to ±{},", "GRID_OVER": "up to **{}** above the fine", "GRID_WHERE": "({})",
    "LAW_P": "p = {} and", "LAW_W": "and w = {}:", "ERR_FIT": "within\n{} on the fitted",
    "ERR_HELD": "{} on the held-out", "WITHIN": "band on {} of the", "HELD": "of the {} held-out",
    "BEYOND": "above it on {} (", "OVER_MAX": "up to {} above the optimum) and", "EDGE": "at the edge on {}.",
    "MARGIN15": "up to {} above the optimum,\n", "STIFF_RANGE": "best X_m is {},", "SOFT_RANGE": "against {} for",
}


def test_the_docs_quote_the_scans():
    text = " ".join((ROOT / "docs" / "design-equations.md").read_text().split())
    wanted = [" ".join(CONTEXT[name].format(value).split()) for name, value in quotes(SCAN["summary"]).items()]
    assert [q for q in wanted if q not in text] == []
