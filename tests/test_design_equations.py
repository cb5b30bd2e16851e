"""Design equations (impact.stages.design.equations): the shipped fit is the charts', it holds on a design it
never saw, and it refuses what it does not cover."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from impact.cli import main
from impact.closed_form.tmd_minimax import tmd_optimum
from impact.model.params import ParameterError
from impact.stages.design.equations.formulas import (
    Point,
    direct_xm,
    evaluate,
    fit,
    formula_gap,
    formula_xm,
    optimum,
    plateau_factors,
    stored,
    tmd_equations,
)

ROOT = Path(__file__).resolve().parents[1]
STUDY = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
FITS = stored()


@pytest.mark.parametrize("kind", sorted(FITS))
def test_the_shipped_coefficients_are_the_fit_of_its_chart_optima(kind):
    entry = FITS[kind]
    again = fit(kind, entry["points"])
    assert set(again) == set(entry["coefficients"])
    np.testing.assert_allclose([again[n] for n in sorted(again)], [entry["coefficients"][n] for n in sorted(again)],
                               rtol=1e-7)
    np.testing.assert_allclose(plateau_factors(entry["points"]), entry["plateau_factors"], rtol=1e-7)


@pytest.mark.parametrize("index", [0, 7])
def test_the_shipped_chart_optima_are_what_the_engine_simulates_under_the_study_config(index):
    """The fit's data are the design charts' runs: a stored optimum, simulated again at its gap ratio under
    config/config.yaml, is the same X_m (a stale fit after a change of the protocol or the engine fails here)."""
    row = FITS["cid"]["points"][index]
    pt = Point(row["mu"], row["e"], row["beta"])
    again = direct_xm(STUDY, "cid", pt, [row["gap_ratio"]])[0]
    assert again == pytest.approx(row["X_m"], rel=1e-9)


def test_the_cid_formula_holds_on_a_design_off_its_charts():
    """A design at other damping and restitution than any chart row (not among the stage's checks either):
    the formula's X_m is within its stated bound of a direct sweep at its gap, from the protocol's starts, and
    within 10 % of the least X_m over the gap ratios (the gap grid, refined around its best)."""
    pt = Point(mu=0.025, e=0.5, beta=0.008)
    answer = evaluate("cid", pt)
    at_formula_gap = direct_xm(STUDY, "cid", pt, [answer["gap_ratio"]])[0]
    assert abs(answer["X_m"] - at_formula_gap) <= answer["error_bound"] * at_formula_gap
    best = optimum(STUDY, "cid", pt)
    assert best["X_m"] <= best["grid_X_m"]
    assert at_formula_gap <= 1.1 * best["X_m"], (at_formula_gap, best)


@pytest.mark.parametrize(("field", "value"), [("mu", 0.2), ("e", 0.9), ("beta", 0.05), ("mu", float("nan"))])
def test_the_formula_refuses_an_input_outside_its_range_by_name(field, value):
    kw = {"mu": 0.01, "e": 0.25, "beta": 0.0048} | {field: value}
    lo, hi = FITS["cid"]["ranges"][field]
    with pytest.raises(ParameterError, match=rf"^{field} = .* allowed \[{lo:g}, {hi:g}\]"):
        evaluate("cid", Point(**kw))


def test_a_kind_whose_formula_failed_its_checks_returns_no_value_and_says_why():
    unpublished = {**FITS["cid"], "published": False, "reason": "its X_m is off direct simulation by up to 51%"}
    with pytest.raises(ParameterError, match="the CID has no design equation: its X_m is off .* 51%"):
        evaluate("cid", Point(0.01, 0.25, 0.0048), {"cid": unpublished})
    with pytest.raises(ParameterError, match="damper = 'tmd' has no design equation"):
        evaluate("tmd", Point(0.01, 0.25, 0.0048))


def test_the_plateau_bound_brackets_the_formulas_gap():
    answer = evaluate("cid", Point(0.02, 0.35, 0.0048))
    lo, hi = answer["plateau"]
    assert lo <= answer["gap_ratio"] <= hi


def test_more_mass_and_less_restitution_lower_the_formulas_x_m():
    """The energy balance's direction: the impacts' loss grows with mu and with 1 - e, the structure's with beta."""
    c = FITS["cid"]["coefficients"]
    base = formula_xm(c, Point(0.01, 0.45, 0.005))
    assert formula_xm(c, Point(0.02, 0.45, 0.005)) < base
    assert formula_xm(c, Point(0.01, 0.25, 0.005)) < base
    assert formula_xm(c, Point(0.01, 0.45, 0.01)) > base
    assert formula_gap(c, 0.5, Point(0.01, 0.45, 0.005)) < formula_gap(c, 0.6, Point(0.01, 0.45, 0.005))


def test_den_hartogs_tmd_is_at_most_a_few_percent_above_the_equal_peak_optimum():
    dh = tmd_equations(0.02, 0.0048)
    optimum = tmd_optimum(0.02, 0.0048)
    assert optimum["X_m"] <= dh["X_m"] <= 1.05 * optimum["X_m"]


def test_impact_design_equations_prints_the_keys_a_script_reads(capsys):
    main(["design", "--equations", "--mu", "0.02", "--e", "0.45", "--json", "--charts", "/nonexistent"])
    out = json.loads(capsys.readouterr().out)
    assert {"gap_ratio", "X_m", "error_bound", "plateau"} <= set(out)
    assert out["X_m"] == pytest.approx(formula_xm(FITS["cid"]["coefficients"], Point(0.02, 0.45, 0.0048)))
    assert out["chart"] is None


def test_impact_design_equations_refuses_out_of_range_by_name(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["design", "--equations", "--mu", "0.2"])
    assert stop.value.code == 2
    assert "mu = 0.2 is out of the CID design equation's range" in capsys.readouterr().err


def test_the_docs_quote_the_shipped_fit():
    """docs/design-equations.md's coefficient table and errors are the shipped fit's, to the digits shown."""
    text = (ROOT / "docs" / "design-equations.md").read_text()
    entry = FITS["cid"]
    for name, value in entry["coefficients"].items():
        assert re.search(rf"\| {name} \| {value:.4g} \|", text), name
    above, grid_over = entry["above_optimum_max"], max(r.get("grid_X_m", r["X_m"]) / r["X_m"] for r in entry["points"])
    low, high = entry["plateau_factors"]
    quoted = [f"within **{entry['error_max']:.1%}**", f"({entry['error_p95']:.1%} on 95%",
              f"within **{entry['error_bound']:.1%}**", f"within {entry['above_optimum_held_out_max']:.0%} of the least",
              f"X_m {above:.0%} above the optimum", f"(the {above:.0%} above)", f"L = {low:.3f} and U = {high:.3f}",
              f"up to {grid_over - 1.0:.0%} above it", f"**{FITS['pid']['error_bound']:.0%}**",
              f"on {entry['checks']} designs held out", f"({len(entry['points'])} designs;"]
    text = " ".join(text.split())
    assert [q for q in quoted if q not in text] == []
