"""Design equations: the optimum gap ratio, X_m at it and its plateau as formulas (docs/design-equations.md).

One form for both walled dampers, a CID being a pendulum with r' = 0:

    X_m  = 1 / (1 + a (mu / beta)^p (1 - e)^s exp(-t r'))
    g_opt = b X_m^c exp(-v r')

The first is an energy balance at resonance: the structure's viscous loss 2 beta X^2 against the impacts'
momentum exchange, proportional to mu X^2 and to how much of each impact's momentum the restitution keeps
from coming back (1 - e).  The second says that the damper mass crosses its gap in about half a period at
the structure's velocity, so the best gap grows with the structure's amplitude.  a, p, s (t) and b, c (v)
are fitted on the design charts' optima (each the worst over the starts), each read again between its grid
neighbours on a fine step (:func:`refined`: the optimum lies between the grid's gap ratios); the rows of e held out of the fit
and the configured checks off the charts give the stated error.  A kind whose held-out error exceeds the
configured acceptance has no published formula: :func:`evaluate` refuses it with the measured error.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from importlib import resources

import numpy as np
import xarray as xr
from scipy.optimize import least_squares

from impact.closed_form.tmd import den_hartog
from impact.closed_form.tmd_minimax import tmd_peak
from impact.model.kinds import KINDS, TMD
from impact.model.params import ParameterError
from impact.stages.design import chart_config
from impact.stages.sweeps import gap_grid, run_curve

#: the study's fit as the package ships it for `impact design --equations` (results/design/equations.json, copied)
STORED = "fit.json"


def coefficients(kind: str) -> tuple[str, ...]:
    """The fitted coefficients of an impact damper's form, in order; the tuning terms t and v only where r'
    varies (a kind with a spring)."""
    return ("a", "p", "s", "t", "b", "c", "v") if KINDS[kind].spring else ("a", "p", "s", "b", "c")


def inputs(kind: str) -> tuple[str, ...]:
    """The inputs an impact damper's formula takes (the ranges in the configuration bound each): r' for a kind
    with a spring."""
    return ("mu", "e", "beta") + ("rp",) * KINDS[kind].spring


@dataclass(frozen=True)
class Point:
    """A damper design's parameters (rp = 0 for the CID)."""

    mu: float
    e: float
    beta: float
    rp: float = 0.0


def _coef(coefs: dict, name: str) -> float:
    return float(coefs.get(name, 0.0))


def formula_xm(coefs: dict, pt: Point) -> float:
    """X_m at the optimum gap by the form's energy balance."""
    pi = (pt.mu / pt.beta) ** _coef(coefs, "p") * (1.0 - pt.e) ** _coef(coefs, "s")
    return 1.0 / (1.0 + _coef(coefs, "a") * pi * math.exp(-_coef(coefs, "t") * pt.rp))


def formula_gap(coefs: dict, xm: float, pt: Point) -> float:
    """The optimum gap ratio, from X_m at it."""
    return _coef(coefs, "b") * xm ** _coef(coefs, "c") * math.exp(-_coef(coefs, "v") * pt.rp)


# ----------------------------------------------------------------------------
# the fit, on the charts' optima
# ----------------------------------------------------------------------------

def _least_on_curve(gaps: np.ndarray, values: np.ndarray, plateau: float) -> dict:
    """The least X_m over a curve of gap ratios, its gap and the plateau around it (see chart_optima)."""
    best = int(np.nanargmin(values))
    level = (1.0 + plateau) * values[best]
    return {"X_m": float(values[best]), "gap_ratio": float(gaps[best]),
            "plateau_low": _crossing(gaps, values, best, level, -1),
            "plateau_high": _crossing(gaps, values, best, level, +1), "on_edge": best in (0, len(gaps) - 1)}


def chart_optima(chart: xr.Dataset, plateau: float) -> list[dict]:
    """Every (e, mu[, r']) of a chart: its best gap ratio, X_m there and the plateau around it, on the chart's grid.

    The plateau's ends are where X_m, linear between the chart's gap ratios, first rises to (1 + plateau) times
    the optimum on either side (the grid's end where it does not).  Optima on the edge of the gap grid are
    marked (`on_edge`): the true optimum may lie beyond it.  `refined` reads each again between its neighbours."""
    beta = float(chart.attrs["beta"])
    gaps = chart["gap_ratio"].values
    xm = chart["X_m"]
    out = []
    for index in np.ndindex(xm.shape[:-1]):
        params = {name: float(chart[name].values[i]) for name, i in zip(xm.dims[:-1], index)}
        out.append({**params, "beta": beta, "rp": params.get("rp", 0.0),
                    **_least_on_curve(gaps, xm.values[index], plateau), "gaps": gaps, "values": xm.values[index]})
    return out


def refined_curve(cfg: dict, kind: str, pt: Point, gaps: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A curve of X_m over the grid's gap ratios with the stretch between its least value's two neighbours read
    again by direct sweeps on design.equations.refine_step (that least value's own gap among them).

    The optimum lies between the grid's gap ratios: a soft PID's at the edge of a cliff, where one hundredth of a
    gap ratio lower X_m is several times higher, and the grid's best well above it, a CID's too
    (docs/design-equations.md says by how much).  A formula is fitted on, and checked against, the optimum itself."""
    i = int(np.nanargmin(values))
    step = cfg["design"]["equations"]["refine_step"]
    # one step beyond the grid where the least value is at its end, so that the fine points hold that value's gap
    lo = gaps[i - 1] if i > 0 else gaps[i] - step
    hi = gaps[i + 1] if i < len(gaps) - 1 else gaps[i] + step
    fine = np.round(np.arange(lo + step, hi - step / 2, step), 9)
    merged_g = np.concatenate([gaps[gaps != gaps[i]], fine])
    merged_x = np.concatenate([values[gaps != gaps[i]], direct_xm(cfg, kind, pt, fine)])
    order = np.argsort(merged_g, kind="stable")
    return merged_g[order], merged_x[order]


def refined(cfg: dict, kind: str, row: dict) -> dict:
    """A grid optimum (a chart_optima row, with its curve) read on its refined curve (refined_curve); the grid's
    optimum is kept beside it.  An optimum on the grid's edge is left as it is (the grid does not bracket it)."""
    out = {k: v for k, v in row.items() if k not in ("gaps", "values")}
    if row["on_edge"]:
        return out
    gaps, values = refined_curve(cfg, kind, _point(row), np.asarray(row["gaps"]), np.asarray(row["values"]))
    return {**out, **_least_on_curve(gaps, values, cfg["design"]["equations"]["plateau"]),
            "grid_X_m": row["X_m"], "grid_gap_ratio": row["gap_ratio"]}


def _crossing(gaps: np.ndarray, values: np.ndarray, best: int, level: float, step: int) -> float:
    """Where X_m, linear between grid points, first reaches `level` walking from the optimum in direction step."""
    i = best
    while 0 <= i + step < len(gaps) and values[i + step] < level:
        i += step
    if not 0 <= i + step < len(gaps):
        return float(gaps[i])
    j = i + step
    return float(gaps[i] + (gaps[j] - gaps[i]) * (level - values[i]) / (values[j] - values[i]))


def _point(row: dict) -> Point:
    return Point(row["mu"], row["e"], row["beta"], row.get("rp", 0.0))


def fit(kind: str, rows: list[dict]) -> dict:
    """The form's coefficients by least squares on log X_m and log g over the rows (not on the chart's edge).

    Raises ParameterError when the rows are fewer than the coefficients they must determine."""
    names = coefficients(kind)
    rows = [r for r in rows if not r["on_edge"]]
    xm_names = [n for n in names if n in ("a", "p", "s", "t")]
    gap_names = [n for n in names if n in ("b", "c", "v")]
    if len(rows) <= len(xm_names):
        raise ParameterError(f"design equations for the {kind}: {len(rows)} chart optima cannot determine "
                             f"{len(xm_names)} coefficients {', '.join(xm_names)}; configure more of design.mu and e")
    points = [_point(r) for r in rows]
    xm = np.array([r["X_m"] for r in rows])
    gap = np.array([r["gap_ratio"] for r in rows])

    def xm_residual(x):
        coefs = dict(zip(xm_names, x))
        return np.log([formula_xm(coefs, pt) for pt in points]) - np.log(xm)

    start = {"a": 1.0, "p": 1.0, "s": 1.0, "t": 1.0}
    xm_fit = least_squares(xm_residual, [start[n] for n in xm_names], x_scale="jac", xtol=1e-14, ftol=1e-14)
    # log g = log b + c log X_m - v r': linear in the coefficients, so solved exactly
    columns = {"b": np.ones_like(xm), "c": np.log(xm), "v": -np.array([pt.rp for pt in points])}
    gap_fit, *_ = np.linalg.lstsq(np.column_stack([columns[n] for n in gap_names]), np.log(gap), rcond=None)
    coefs = dict(zip(xm_names, (float(x) for x in xm_fit.x)))
    coefs.update(zip(gap_names, (float(x) for x in gap_fit)))
    coefs["b"] = math.exp(coefs["b"])
    return {n: coefs[n] for n in names}


def plateau_factors(rows: list[dict]) -> tuple[float, float]:
    """(L, U): on every row, the gap ratios from L g_opt to U g_opt (g_opt the row's own optimum) kept X_m within
    the plateau's tolerance of the optimum: the band of gaps, relative to the optimum, that every fitted design
    tolerates (the paper's measure of insensitivity to the force's amplitude, as a bound)."""
    rows = [r for r in rows if not r["on_edge"]]
    return max(r["plateau_low"] / r["gap_ratio"] for r in rows), min(r["plateau_high"] / r["gap_ratio"] for r in rows)


# ----------------------------------------------------------------------------
# the checks: direct simulation at the formula's gap, against the best over the gap grid
# ----------------------------------------------------------------------------

def _curve_config(cfg: dict, beta: float) -> dict:
    """The charts' configuration (their frequency window and protocol) for a structure of damping beta."""
    chart_cfg = chart_config(cfg)
    return {**chart_cfg, "structure": {**chart_cfg["structure"], "beta": beta}}


def _spec(kind: str, pt: Point) -> dict:
    spec = {"damper": kind, "mu": pt.mu, "e": pt.e}
    return {**spec, "rp": pt.rp} if KINDS[kind].spring else spec


def direct_xm(cfg: dict, kind: str, pt: Point, gap_ratios) -> np.ndarray:
    """X_m at each gap ratio by direct sweeps on the charts' frequency window, the worst over the starts (the
    chart's own reading, the refined peak)."""
    ds = run_curve(_curve_config(cfg, pt.beta), _spec(kind, pt), gap_ratios=gap_ratios)
    return ds["X_m_refined"].max("start").values


def optimum(cfg: dict, kind: str, pt: Point) -> dict:
    """The least X_m over the gap ratios by direct sweeps: the protocol's gap grid, then refined (see refined)."""
    gaps = gap_grid(cfg)
    scan = direct_xm(cfg, kind, pt, gaps)
    row = {"mu": pt.mu, "e": pt.e, "beta": pt.beta, "rp": pt.rp, "gaps": gaps, "values": scan,
           **_least_on_curve(gaps, scan, cfg["design"]["equations"]["plateau"])}
    return refined(cfg, kind, row)


def check_point(cfg: dict, kind: str, coefs: dict, pt: Point, best: dict | None = None) -> dict:
    """The formula at one held-out point against simulation: X_m at the formula's gap, and the optimum over the
    gap ratios (a refined chart row when given, else found by direct sweeps: optimum)."""
    xm_f = formula_xm(coefs, pt)
    g_f = formula_gap(coefs, xm_f, pt)
    xm_at_g = float(direct_xm(cfg, kind, pt, [g_f])[0])
    best = optimum(cfg, kind, pt) if best is None else best
    return {"mu": pt.mu, "e": pt.e, "beta": pt.beta, "rp": pt.rp, "X_m_formula": xm_f, "gap_ratio_formula": g_f,
            "X_m_at_formula_gap": xm_at_g, "X_m_best": best["X_m"], "gap_ratio_best": best["gap_ratio"],
            "error": abs(xm_f - xm_at_g) / xm_at_g, "above_optimum": xm_at_g / best["X_m"] - 1.0}


def _verdict(checks: list[dict], acceptable: float) -> dict:
    """The stated error: over the held-out checks (the issue's measure) and over every point checked, the
    fitted ones too (the bound a user is given); and whether it lets the formula be published."""
    held = [c for c in checks if c["held_out"]]
    if not held:
        return {"error_max": None, "error_p95": None, "error_bound": None, "above_optimum_max": None,
                "above_optimum_held_out_max": None, "checks": 0, "published": False,
                "reason": "no held-out point checks it (design.equations: holdout_e and checks)"}
    errors = np.array([c["error"] for c in held])
    stated = {"error_max": float(errors.max()), "error_p95": float(np.percentile(errors, 95)),
              "error_bound": float(max(c["error"] for c in checks)),
              "above_optimum_max": float(max(c["above_optimum"] for c in checks)),
              "above_optimum_held_out_max": float(max(c["above_optimum"] for c in held)), "checks": len(held)}
    published = stated["error_bound"] <= acceptable
    reason = None if published else (f"its X_m is off direct simulation by up to {stated['error_bound']:.0%}, "
                                     f"above the acceptable {acceptable:.0%}")
    return {**stated, "published": bool(published), "reason": reason}


def study_kind(cfg: dict, kind: str, chart: xr.Dataset, stored_entry: dict | None) -> tuple[dict, list[dict]]:
    """One kind's formula: fitted on the chart's optima outside the held-out rows of e (or, where those are too
    few to determine it, the stored fit), then checked on the held-out rows and the configured points."""
    eq = cfg["design"]["equations"]
    rows = [refined(cfg, kind, row) for row in chart_optima(chart, eq["plateau"])]
    held_e = set(eq["holdout_e"])
    train = [r for r in rows if r["e"] not in held_e]
    try:
        coefs, fitted = fit(kind, train), True
    except ParameterError:
        if stored_entry is None:
            raise
        coefs, fitted = stored_entry["coefficients"], False
    on_chart = [(r, r["e"] in held_e) for r in rows if not r["on_edge"]]
    checks = [check_point(cfg, kind, coefs, _point(r), best=r) | {"held_out": held} for r, held in on_chart]
    checks += [check_point(cfg, kind, coefs, Point(**c)) | {"held_out": True} for c in eq["checks"].get(kind, [])]
    plateau = plateau_factors(train) if any(not r["on_edge"] for r in train) else None
    entry = {"kind": kind, "coefficients": coefs, "fitted": fitted,
             "ranges": {name: list(eq["ranges"][name]) for name in inputs(kind)},
             "chart_beta": float(chart.attrs["beta"]), **_verdict(checks, eq["acceptable_error"]),
             "plateau_tolerance": eq["plateau"], "plateau_factors": list(plateau) if plateau else None,
             "points": train}
    return entry, checks


CHECK_ATTRS = {
    "mu": ("mass ratio of the damper, m / M", "1"), "e": ("coefficient of restitution", "1"),
    "beta": ("structural damping ratio", "1"), "rp": ("pendulum tuning r' (0 for the CID)", "1"),
    "X_m_formula": ("X_m by the design equation", "1"),
    "gap_ratio_formula": ("optimum gap ratio by the design equation", "1"),
    "X_m_at_formula_gap": ("X_m simulated at the formula's gap ratio, the worst over the starts", "1"),
    "X_m_best": ("the least X_m over the gap ratios, simulated (the gap grid, refined around its best)", "1"),
    "gap_ratio_best": ("the gap ratio of the least X_m, simulated (the gap grid, refined around its best)", "1"),
    "error": ("|X_m by the formula - X_m simulated at its gap| / X_m simulated", "1"),
    "above_optimum": ("X_m simulated at the formula's gap over the least X_m, less one", "1"),
    "held_out": ("whether the point was kept out of the fit (1) or fitted (0)", "1"),
}


def checks_dataset(fits: dict, checks: dict) -> xr.Dataset:
    """The held-out checks of every kind, one row each, and the fits as attributes."""
    rows = [(kind, c) for kind, kind_checks in checks.items() for c in kind_checks]
    data = {name: ("check", np.array([c[name] for _, c in rows], dtype=float), {"long_name": ln, "units": u})
            for name, (ln, u) in CHECK_ATTRS.items()}
    data["kind"] = ("check", np.array([kind for kind, _ in rows], dtype=str), {"long_name": "damper type"})
    ds = xr.Dataset(data, coords={"check": ("check", np.arange(len(rows)), {"long_name": "held-out check", "units": "1"})})
    ds.attrs.update(title="Design equations against direct simulation on held-out points",
                    fits=json.dumps({k: {n: v for n, v in f.items() if n != "points"} for k, f in fits.items()}))
    return ds


# ----------------------------------------------------------------------------
# reading a formula: `impact design --equations`
# ----------------------------------------------------------------------------

def stored() -> dict:
    """The study's fit as shipped with the package (results/design/equations.json of the full study)."""
    return json.loads(resources.files("impact.stages.design.equations").joinpath(STORED).read_text())


def _check_ranges(kind: str, entry: dict, pt: Point) -> None:
    for name in inputs(kind):
        lo, hi = entry["ranges"][name]
        value = getattr(pt, name)
        if not (math.isfinite(value) and lo <= value <= hi):
            raise ParameterError(f"{name} = {value!r} is out of the {kind.upper()} design equation's range: "
                                 f"allowed [{lo:g}, {hi:g}] (the range it was fitted and checked on)")


def evaluate(kind: str, pt: Point, fits: dict | None = None) -> dict:
    """The formula's optimum gap ratio, X_m there, its plateau and its stated error, for one design.

    Refuses (ParameterError, naming the field) an input outside the formula's range, and a kind whose formula
    was not published (its held-out error above the acceptance), with the reason."""
    fits = stored() if fits is None else fits
    if kind not in fits:
        raise ParameterError(f"damper = {kind!r} has no design equation: choose one of {', '.join(fits)}")
    entry = fits[kind]
    if not entry["published"]:
        raise ParameterError(f"the {kind.upper()} has no design equation: {entry['reason']}; read its design "
                             "chart instead (impact design --target-xm)")
    _check_ranges(kind, entry, pt)
    coefs = entry["coefficients"]
    xm = formula_xm(coefs, pt)
    g = formula_gap(coefs, xm, pt)
    lo, hi = entry["plateau_factors"] if entry["plateau_factors"] else (1.0, 1.0)
    return {"damper": kind, "mu": pt.mu, "e": pt.e, "beta": pt.beta, **({"rp": pt.rp} if KINDS[kind].spring else {}),
            "gap_ratio": g, "X_m": xm, "error_bound": entry["error_bound"], "error_held_out_max": entry["error_max"],
            "error_held_out_p95": entry["error_p95"],
            "plateau": [lo * g, hi * g], "plateau_tolerance": entry["plateau_tolerance"]}


def tmd_equations(mu: float, beta: float) -> dict:
    """Den Hartog's formulas for the TMD beside the impact dampers': its tuning and damping, and X_m at them
    (the linear closed form's true peak over r = 0.5 to 1.5, so exact; it is not the equal-peak optimum's,
    which the TMD chart holds)."""
    dh = den_hartog(mu)
    peak = tmd_peak(mu, beta, dh["f"], dh["beta_t"], force_ratio=1.0)[1]
    return {"damper": TMD, "mu": mu, "beta": beta, "tuning": dh["f"], "damping": dh["beta_t"], "gap_ratio": None,
            "X_m": peak * 2.0 * beta, "error_bound": 0.0, "plateau": None}
