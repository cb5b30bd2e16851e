"""Designs from the command line: impact design, read off the study's design charts and checked by one direct
simulation, or with --equations the design equations' answer."""

from __future__ import annotations

import sys
from pathlib import Path

from impact.cli.flags import CHARTS
from impact.model.kinds import CID, KINDS
from impact.model.params import ParameterError
from impact.model.scene import DAMPER_KINDS
from impact.stages.design import DesignError, load_charts
from impact.stages.design import design as design_from_charts
from impact.stages.design.equations.formulas import Point, evaluate, tmd_equations


def _default_charts() -> Path:
    """The design charts of the study in this folder, else of the source tree this package runs from (an
    editable install: `impact design` then works from any folder once the study has run)."""
    here = Path.cwd() / CHARTS
    source_tree = Path(__file__).resolve().parents[3] / CHARTS
    return here if here.is_dir() or not source_tree.is_dir() else source_tree


def design(args) -> dict | str:
    """The smallest damper on the charts that meets --target-xm, checked by one direct simulation; with
    --equations, the design equations' answer instead."""
    if args.equations:
        answer = _design_equations(args)
        return answer if args.json else _equations_text(answer)
    if args.target_xm is None:
        raise ParameterError("--target-xm is required (or ask the design equations with --equations)")
    charts = load_charts(args.charts or _default_charts(), (args.damper,) if args.damper else DAMPER_KINDS)
    try:
        answer = design_from_charts(charts, args.target_xm, amplitude_range=args.amplitude_range, refinement=args.refinement)
    except DesignError as exc:
        print(f"impact design: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    return answer if args.json else _design_text(answer)


def _design_equations(args) -> dict:
    """The design equation of --damper (the CID by default) at the flags' design, with the chart's own optimum
    beside it when the charts hold that design (its mu, e, r' on their grid and their damping)."""
    kind = args.damper or CID
    if not KINDS[kind].walls:
        return tmd_equations(args.mu, args.beta)
    answer = evaluate(kind, Point(args.mu, args.e, args.beta, args.rp if KINDS[kind].spring else 0.0))
    try:
        chart = load_charts(args.charts or _default_charts(), (kind,))[kind]
    except ParameterError:
        return answer | {"chart": None}
    return answer | {"chart": _chart_optimum(chart, answer)}


def _chart_optimum(chart, answer: dict) -> dict | None:
    """The chart's best gap ratio and X_m at the answer's design, if the chart holds it (else None)."""
    if abs(float(chart.attrs["beta"]) - answer["beta"]) > 1e-12:
        return None
    at = {}
    for name in chart["X_m_best"].dims:
        grid = chart[name].values
        match = [v for v in grid if abs(v - answer[name]) <= 1e-9 * max(abs(v), 1.0)]
        if not match:
            return None
        at[name] = match[0]
    return {"gap_ratio": float(chart["gap_ratio_best"].sel(at)), "X_m": float(chart["X_m_best"].sel(at)),
            "gap_step": float(chart["gap_ratio"].values[1] - chart["gap_ratio"].values[0])}


def _equations_text(a: dict) -> str:
    """The design equation's answer as a person reads it."""
    if not KINDS[a["damper"]].walls:
        return (f"TMD, mu = {a['mu']:g}: Den Hartog's tuning f = {a['tuning']:.4f}, damping beta_t = "
                f"{a['damping']:.4f}; X_m there {a['X_m']:.4f} (exact, linear closed form)")
    lines = [f"{a['damper'].upper()}, mu = {a['mu']:g}, e = {a['e']:g}, beta = {a['beta']:g}"
             + (f", r' = {a['rp']:g}" if "rp" in a else ""),
             f"  optimum gap ratio g = {a['gap_ratio']:.3f}, X_m = {a['X_m']:.4f} (within {a['error_bound']:.1%} of "
             f"simulation at every point checked; on the points held out of the fit, {a['error_held_out_max']:.1%} "
             f"at most and {a['error_held_out_p95']:.1%} on 95 % of them)"]
    if a["plateau"]:
        lines.append(f"  X_m within {a['plateau_tolerance']:.0%} of the optimum for g in {a['plateau'][0]:.3f} to "
                     f"{a['plateau'][1]:.3f} (a bound)")
    if a.get("chart"):
        lines.append(f"  the chart: g = {a['chart']['gap_ratio']:g} (its grid's step {a['chart']['gap_step']:g}), "
                     f"X_m = {a['chart']['X_m']:.4f}")
    return "\n".join(lines)


def _design_text(a: dict) -> str:
    """The answer as a person reads it, with the `impact sweep` flags that rerun it."""
    if not KINDS[a["damper"]].walls:
        what = f"TMD, mu = {a['mu']:g}, tuning f = {a['tuning']:.4f}, damping beta_t = {a['damping']:.4f}"
        again = ""
    else:
        flags = {"damper": a["damper"], "mu": a["mu"], "e": a["e"], "gap-ratio": a["gap_ratio"], "rp": a.get("rp"),
                 "r-min": a["r_min"], "r-max": a["r_max"]}
        what = ", ".join(f"{k} = {v:g}" for k, v in (("mu", a["mu"]), ("g", a["gap_ratio"]), ("e", a["e"]),
                                                      ("r'", a.get("rp"))) if v is not None)
        what = f"{a['damper'].upper()}, {what}"
        again = ("\n  rerun it:  impact sweep " + " ".join(f"--{k} {v}" for k, v in flags.items() if v is not None)
                 + f"  (one start per sweep: --start {' or '.join(a['starts'])})")
    lines = [f"{what}", f"  X_m {a['xm_chart']:.4f} on the chart, {a['xm_simulated']:.4f} simulated "
             f"(target {a['target_xm']:g}, margin {a['margin_simulated']:.4f})"]
    if "xm_chart_range" in a:
        lines.append(f"  over force scales {a['amplitude_range'][0]:g} to {a['amplitude_range'][1]:g}: worst X_m "
                     f"{a['xm_chart_range']:.4f} on the chart (at scale {a['worst_scale']:.3g})"
                     + (f", {a['xm_simulated_range']:.4f} simulated" if "xm_simulated_range" in a else ""))
    if a["rejected"]:
        lines.append(f"  {len(a['rejected'])} lighter chart design(s) failed their direct simulation")
    lines.append(f"  for {a['design_point']}")
    return "\n".join(lines) + again
