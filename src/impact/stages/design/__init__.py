"""Design charts, and the smallest damper that meets a target X_m.

A chart is the study's own sweeps read as a map for a designer: X_m of the CID over (e, mu, g), of the PID
over (e, mu, r', g), each the worst over the configured starts of the damper mass (nobody controls where it
sits when the load begins), and of the TMD at its equal-peak optimum over mu.  X_m is the refined peak
(:mod:`impact.stages.readings`) of the paper's protocol on the paper's structure, which every chart cites in its
attributes.

Over a range of force amplitudes the charts answer without a new run, by an exact similarity: the CID and
PID are linear between impacts and their impacts are rigid, so scaling the force by s with the physical
gap d fixed is the design force with the gap ratio g / s, and X_m(s, g) = X_m(1, g / s).  The TMD is linear:
its X_m does not depend on s.

:func:`design` picks the smallest mass ratio (then the largest margin) whose chart value meets the target,
and checks it by one direct simulation on a frequency grid finer than the chart's.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from impact.closed_form.tmd_minimax import tmd_optimum, tmd_peak
from impact.engine.run import sweep
from impact.model.kinds import KINDS, TMD
from impact.model.params import ParameterError, Protocol, System, a_max, frequency_grid
from impact.model.scene import DAMPER_KINDS
from impact.stages.curves import curve_specs
from impact.stages.robustness.designs import Design
from impact.stages.robustness.runs import scene_peak_response

READING = "X_m_refined"   # the chart's X_m: each start's refined peak over the frequency grid
MAX_CHECKS = 5            # chart designs tried by direct simulation before giving up


class DesignError(ValueError):
    """A target the charts cannot meet; the message gives the best X_m they reach."""


# ----------------------------------------------------------------------------
# the charts' curves and datasets
# ----------------------------------------------------------------------------

def chart_specs(design_cfg: dict, kind: str) -> list[dict]:
    """The sweep curves an impact damper's chart reads: every (e, mu[, r']) of the design section, r' (the
    design section's pid_tunings) for a kind with a spring."""
    return curve_specs((kind,), design_cfg["mu"], design_cfg["e"], design_cfg["pid_tunings"])


def chart_config(cfg: dict) -> dict:
    """The study's configuration with the charts' own frequency window, which their sweeps run on.

    Wider than the paper's (0.9 to 1.1): a PID tuned to the structure with a few per cent of its mass splits
    the resonance into two peaks about 1 +- sqrt(mu) / 2, outside the paper's window above mu = 0.03."""
    return {**cfg, "protocol": {**cfg["protocol"], "freq": cfg["design"]["freq"]}}


def _axes(kind: str, specs: list[dict]) -> dict:
    axes = {"e": sorted({s["e"] for s in specs}), "mu": sorted({s["mu"] for s in specs})}
    if KINDS[kind].spring:
        axes["rp"] = sorted({s["rp"] for s in specs})
    return axes


AXIS_ATTRS = {
    "e": {"long_name": "coefficient of restitution", "units": "1"},
    "mu": {"long_name": "mass ratio of the damper, m / M", "units": "1"},
    "rp": {"long_name": "pendulum tuning r' = omega_p / omega", "units": "1"},
    "gap_ratio": {"long_name": "gap ratio g = d / A_max at the design force", "units": "1"},
}


def impact_chart(kind: str, sweeps: list) -> xr.Dataset:
    """A CID or PID chart from its sweep datasets (one per (e, mu[, r'])), each with every start and gap."""
    specs = [json.loads(ds.attrs["curve"]) for ds in sweeps]
    axes = _axes(kind, specs)
    first = sweeps[0]
    gaps, starts = first["gap_ratio"].values, [str(s) for s in first["start"].values]
    shape = tuple(len(v) for v in axes.values())
    per_start = np.full((len(starts), *shape, len(gaps)), np.nan)
    for spec, ds in zip(specs, sweeps):
        if not np.array_equal(ds["gap_ratio"].values, gaps) or [str(s) for s in ds["start"].values] != starts:
            raise ValueError(f"chart {kind}: curve {spec} has another gap grid or other starts than {specs[0]}")
        index = tuple(axes[name].index(spec[name]) for name in axes)
        per_start[(slice(None), *index)] = ds[READING].values
    dims = (*axes, "gap_ratio")
    worst = np.max(per_start, axis=0)
    best_i = np.argmin(np.where(np.isfinite(worst), worst, np.inf), axis=-1)
    data = {
        "X_m_start": (("start", *dims), per_start,
                      {"long_name": "X_m from one start of the damper mass (refined peak over r)", "units": "1"}),
        "X_m": (dims, worst, {"long_name": "X_m, the worst over the starts", "units": "1"}),
        "X_m_best": (tuple(axes), np.take_along_axis(worst, best_i[..., None], -1)[..., 0],
                     {"long_name": "X_m at the best gap ratio", "units": "1"}),
        "gap_ratio_best": (tuple(axes), gaps[best_i], {"long_name": "the gap ratio with the lowest X_m",
                                                       "units": "1"}),
    }
    coords = {name: (name, values, AXIS_ATTRS[name]) for name, values in axes.items()}
    coords["gap_ratio"] = ("gap_ratio", gaps, AXIS_ATTRS["gap_ratio"])
    coords["start"] = ("start", starts, {"long_name": "initial place of the damper mass"})
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(_design_point(first), kind=kind, title=f"Design chart: X_m of the {kind.upper()}",
                    reading=f"{READING} of each sweep, the worst over the starts")
    return ds


def _design_point(sweep) -> dict:
    """The design point a chart is computed for, from one of its sweeps (all share it)."""
    return design_point(float(sweep.attrs["param_beta"]), float(sweep.attrs["param_force_ratio"]),
                        json.loads(sweep.attrs["protocol"]), sweep["freq_ratio"].values,
                        sweep.attrs["initial_condition"])


def design_point(beta: float, force_ratio: float, protocol: dict, r, initial_condition: str) -> dict:
    """A chart's attributes that say what it was computed for, and how to check it by simulation."""
    step = float(np.round(np.median(np.diff(r)), 12)) if len(r) > 1 else 0.0
    cite = (f"the paper's structure, beta = {beta:g}, F0/K = {force_ratio:g} (A_max = {a_max(beta, force_ratio):g}), "
            f"forced at r = {r[0]:g} to {r[-1]:g}; X_m = x_max / A_max of a {float(protocol['periods']):g}-period "
            f"run from rest, amplitude from period {float(protocol['average_from']):g}")
    return {"beta": beta, "force_ratio": force_ratio, "a_max": a_max(beta, force_ratio),
            "periods": float(protocol["periods"]), "average_from": float(protocol["average_from"]),
            "freq_min": float(r[0]), "freq_max": float(r[-1]), "freq_step": step,
            "initial_condition": initial_condition, "design_point": cite}


def tmd_chart(mu_values, beta: float, force_ratio: float, protocol: dict, r) -> xr.Dataset:
    """The TMD at its equal-peak optimum for each mass ratio: X_m (its true peak), tuning and damping.

    protocol, r: the impact charts' protocol and frequency grid, which its direct check runs."""

    mu_values = np.asarray(mu_values, dtype=float)
    optima = [tmd_optimum(float(mu), beta, force_ratio) for mu in mu_values]
    data = {"X_m": ("mu", [o["X_m"] for o in optima],
                    {"long_name": "X_m of the TMD at its equal-peak optimum (the true peak over r)", "units": "1"}),
            "tuning": ("mu", [o["f"] for o in optima], {"long_name": "TMD tuning f = omega_t / omega", "units": "1"}),
            "damping": ("mu", [o["beta_t"] for o in optima], {"long_name": "TMD damping ratio beta_t",
                                                               "units": "1"})}
    ds = xr.Dataset(data, coords={"mu": ("mu", mu_values, AXIS_ATTRS["mu"])})
    ds.attrs.update(design_point(beta, force_ratio, protocol, r, "structure and TMD at rest"), kind=TMD,
                    title="Design chart: X_m of the TMD at its equal-peak optimum",
                    reading="the equal-peak optimum's largest peak over r = 0.5 to 1.5 (closed form)")
    return ds


def tmd_mu_grid(design_cfg: dict) -> np.ndarray:
    mu = design_cfg["mu"]
    return np.linspace(min(mu), max(mu), int(design_cfg["tmd_points"]))


# ----------------------------------------------------------------------------
# reading a chart: the smallest damper that meets a target
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Candidate:
    """One chart design: its parameters, its X_m at the design force and its worst over the amplitudes."""

    kind: str
    params: dict
    xm_chart: float
    xm_range: float
    worst_scale: float

    @property
    def key(self):
        return (self.params["mu"], self.xm_range)


def _over_amplitudes(xm: np.ndarray, gaps: np.ndarray, amplitude_range) -> tuple[np.ndarray, np.ndarray]:
    """The worst X_m over force scales s in [lo, hi] for each gap ratio g of the last axis, read at g / s
    (exact similarity), and the scale where it is reached.  NaN where g / s leaves the chart's gap grid."""
    if amplitude_range is None:
        return xm, np.ones_like(xm)
    lo, hi = amplitude_range
    worst, where = np.full_like(xm, np.nan), np.full_like(xm, np.nan)
    for i, g in enumerate(gaps):
        g_lo, g_hi = g / hi, g / lo
        if g_lo < gaps[0] - 1e-12 or g_hi > gaps[-1] + 1e-12:
            continue
        inside = gaps[(gaps > g_lo) & (gaps < g_hi)]
        at = np.concatenate(([g_lo], inside, [g_hi]))
        values = np.stack([_interp_last(xm, gaps, x) for x in at], axis=-1)
        j = np.argmax(np.where(np.isfinite(values), values, np.inf), axis=-1)
        worst[..., i] = np.take_along_axis(values, j[..., None], -1)[..., 0]
        where[..., i] = g / at[j]
    return worst, where


def _interp_last(values: np.ndarray, grid: np.ndarray, x: float) -> np.ndarray:
    """Linear interpolation along the last axis at x (NaN propagates from either neighbour)."""
    k = int(np.clip(np.searchsorted(grid, x) - 1, 0, len(grid) - 2))
    w = (x - grid[k]) / (grid[k + 1] - grid[k])
    return (1.0 - w) * values[..., k] + w * values[..., k + 1] if w > 0.0 else values[..., k]


def _impact_candidates(chart, amplitude_range) -> list[Candidate]:
    xm = chart["X_m"]
    gaps = chart["gap_ratio"].values
    worst, scale = _over_amplitudes(xm.values, gaps, amplitude_range)
    out = []
    for index in np.ndindex(worst.shape):
        if not np.isfinite(worst[index]):
            continue
        params = {name: float(chart[name].values[i]) for name, i in zip(xm.dims, index)}
        out.append(Candidate(chart.attrs["kind"], params, float(xm.values[index]), float(worst[index]),
                             float(scale[index])))
    return out


def _tmd_candidates(chart) -> list[Candidate]:
    return [Candidate(TMD, {"mu": float(mu), "tuning": float(f), "damping": float(bt)}, float(x), float(x), 1.0)
            for mu, x, f, bt in zip(chart["mu"].values, chart["X_m"].values, chart["tuning"].values,
                                    chart["damping"].values)]


def candidates(chart, amplitude_range=None) -> list[Candidate]:
    """Every design on a chart, with its X_m at the design force and its worst over the amplitude range."""
    if KINDS[chart.attrs["kind"]].walls:
        return _impact_candidates(chart, amplitude_range)
    return _tmd_candidates(chart)


def _describe(c: Candidate) -> str:
    return f"{c.kind}, " + ", ".join(f"{k} = {v:g}" for k, v in c.params.items())


def ranked(charts: dict, target: float, amplitude_range=None) -> list[Candidate]:
    """The chart designs meeting the target over the range, smallest mass first, then largest margin.

    Raises DesignError, naming the best reachable X_m, if none does."""
    every = [c for chart in charts.values() for c in candidates(chart, amplitude_range)]
    meeting = sorted((c for c in every if c.xm_range <= target), key=lambda c: c.key)
    if meeting:
        return meeting
    if not every:
        raise DesignError("the amplitude range reaches outside every chart's gap grid: no design can be read; "
                          "narrow --amplitude-range")
    best = min(every, key=lambda c: c.xm_range)
    where = "" if amplitude_range is None else f" over force scales {amplitude_range[0]:g} to {amplitude_range[1]:g}"
    raise DesignError(f"target X_m <= {target:g} is not reachable on the charts ({', '.join(charts)}){where}: "
                      f"the best reachable X_m is {best.xm_range:.4g} ({_describe(best)})")


# ----------------------------------------------------------------------------
# the direct check
# ----------------------------------------------------------------------------

def check_grid(chart, refinement: int) -> np.ndarray:
    """The chart's frequency range, on a grid `refinement` times finer than the chart's."""

    lo, hi, step = chart.attrs["freq_min"], chart.attrs["freq_max"], chart.attrs["freq_step"]
    return frequency_grid(lo, hi, step / refinement) if step > 0 else np.array([lo])


def simulate_design(chart, params: dict, refinement: int, scale: float = 1.0) -> float:
    """X_m of one design by direct simulation: every start of the chart, on the refined frequency grid.

    scale: the force over the design force (the physical gap as designed): by similarity, the gap ratio / s."""
    kind, attrs = chart.attrs["kind"], chart.attrs
    protocol = Protocol(periods=attrs["periods"], average_from=attrs["average_from"])
    if not KINDS[kind].walls:
        return _simulate_tmd(chart, params, protocol)

    system = System.from_gap_ratio(kind, mu=params["mu"], beta=attrs["beta"], e=params["e"],
                                   gap_ratio=params["gap_ratio"] / scale, rp=params.get("rp", 0.0),
                                   force_ratio=attrs["force_ratio"])
    grid = check_grid(chart, refinement)
    worst = -math.inf
    for start in chart["start"].values:
        result = sweep(system, grid, Protocol(periods=protocol.periods, average_from=protocol.average_from,
                                              start=str(start)))
        worst = max(worst, result.x_max / system.a_max)
    return worst


def _simulate_tmd(chart, params: dict, protocol: Protocol) -> float:
    """The TMD on the scene core over the chart's frequencies and its two closed-form peaks."""

    attrs = chart.attrs
    design = Design(attrs["kind"], mu=params["mu"], beta=attrs["beta"], tuning=params["tuning"],
                    damping=params["damping"], force_ratio=attrs["force_ratio"])
    # each side's largest peak (equal at the optimum) on the grid too, so the check finds the true maximum
    peaks = [tmd_peak(params["mu"], attrs["beta"], params["tuning"], params["damping"], lo, hi,
                      force_ratio=attrs["force_ratio"])[0] for lo, hi in ((0.5, 1.0), (1.0, 1.5))]
    grid = np.union1d(check_grid(chart, 1), peaks)
    return scene_peak_response(design, grid, protocol)["X_m"]


# ----------------------------------------------------------------------------
# the answer
# ----------------------------------------------------------------------------

def design(charts: dict, target: float, amplitude_range=None, refinement: int = 5,
           max_checks: int = MAX_CHECKS) -> dict:
    """The smallest damper on the charts that meets X_m <= target (over the amplitude range), checked.

    charts: kind -> chart dataset (one or several kinds).  Chart designs are tried in order (smallest mass,
    then largest margin) until one's direct simulation meets the target too; those that did not are listed."""
    if not (target > 0.0 and math.isfinite(target)):
        raise ParameterError(f"target X_m = {target} must be a positive number")
    if amplitude_range is not None and not (0.0 < amplitude_range[0] <= 1.0 <= amplitude_range[1]):
        raise ParameterError(f"amplitude range {amplitude_range} must be lo <= 1 <= hi with lo > 0 "
                             "(scales of the design force)")
    rejected = []
    for cand in ranked(charts, target, amplitude_range)[:max_checks]:
        chart = charts[cand.kind]
        simulated = simulate_design(chart, cand.params, refinement)
        answer = _answer(cand, chart, target, simulated, amplitude_range)
        if amplitude_range is not None and KINDS[cand.kind].walls:
            answer["xm_simulated_range"] = simulate_design(chart, cand.params, refinement, cand.worst_scale)
        if _meets(answer, target):
            answer["rejected"] = rejected
            return answer
        rejected.append(answer)
    raise DesignError(f"no chart design meeting X_m <= {target:g} passed its direct simulation "
                      f"({len(rejected)} tried): " + "; ".join(
                          f"{_describe_answer(a)}: chart {a['xm_chart']:.4g}, simulated {a['xm_simulated']:.4g}"
                          for a in rejected))


def _meets(answer: dict, target: float) -> bool:
    return answer["xm_simulated"] <= target and answer.get("xm_simulated_range", -math.inf) <= target


def _describe_answer(a: dict) -> str:
    return f"{a['damper']} mu = {a['mu']:g}" + (f", g = {a['gap_ratio']:g}" if a["gap_ratio"] is not None else "")


def _answer(cand: Candidate, chart, target: float, simulated: float, amplitude_range) -> dict:
    p = cand.params
    out = {"damper": cand.kind, "mu": p["mu"], "gap_ratio": p.get("gap_ratio"), "e": p.get("e"),
           "target_xm": target, "xm_chart": cand.xm_chart, "xm_simulated": simulated,
           "margin_chart": target - cand.xm_chart, "margin_simulated": target - simulated,
           "design_point": chart.attrs["design_point"]}
    if "rp" in p:
        out["rp"] = p["rp"]
    if not KINDS[cand.kind].walls:
        out.update(tuning=p["tuning"], damping=p["damping"])
    else:
        out["starts"] = [str(s) for s in chart["start"].values]
        out.update(r_min=chart.attrs["freq_min"], r_max=chart.attrs["freq_max"])  # `impact sweep`'s --r-min/--r-max
        out["check"] = (f"every start, r = {chart.attrs['freq_min']:g} to {chart.attrs['freq_max']:g} "
                        "in steps finer than the chart's")
    if amplitude_range is not None:
        out.update(amplitude_range=list(amplitude_range), xm_chart_range=cand.xm_range,
                   worst_scale=cand.worst_scale, margin_chart_range=target - cand.xm_range)
    return out


def load_charts(directory, kinds=DAMPER_KINDS) -> dict:
    """The chart datasets of the given kinds from a directory (results/design by default)."""
    charts = {}
    for kind in kinds:
        path = Path(directory) / f"chart_{kind}.nc"
        if not path.exists():
            raise ParameterError(f"no chart for {kind} at {path}: build it with "
                                 f"`snakemake --cores 2 {path}` or give --charts DIR")
        charts[kind] = xr.load_dataset(path)
    return charts
