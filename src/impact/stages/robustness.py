"""Table 1 of the paper in numbers: how a damper's X_m moves with what its designer does not control.

A :class:`Design` is one damper on the paper's one-storey structure (model units: M = 1, K = 1, so the
structure's frequency is 1), at its design point: the CID and PID at their optimum gap ratio, the TMD at
its equal-peak optimum.  Every measure is the paper's X_m, the largest protocol amplitude over a grid of
forcing frequencies divided by the bare structure's resonant amplitude, taken under changed conditions on
the exact engine (:func:`impact.engine.run.simulate`, which runs the undamped CID and PID, described through an
exact similarity as the paper's system (:func:`paper_system`), on its paper loop):

* the force amplitude scaled by s with the physical gap left as designed (Table 1, row 9);
* the structure's frequency drifted by a factor 1 + delta through its stiffness, the damper left as
  designed, so that its own frequency over the structure's becomes tuning / (1 + delta) (row 6).  X_m is
  then over the drifted structure's own A_max, and the frequency grid is relative to its own frequency,
  so that a damper that loses its tuning shows it, and a stiffer structure is not credited for being stiff;
* the damper's damping ratio (the TMD's beta_t; the PID's pendulum damping, zero in the paper) (row 7);
* the coefficient of restitution (row 10);
* the damper's stroke: its largest displacement relative to the structure over the run (row 5).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import pandas as pd

from impact.engine.run import simulate
from impact.model.building import Building
from impact.model.params import Protocol, System, a_max, check_choice, check_fields
from impact.model.scene import DAMPER_KINDS, Damper, Harmonic, Scene, paper_scene_from_system
from impact.outputs.datasets import optimum

BAND = 0.25   # "X_m stays within 25 % of its design value"


@dataclass(frozen=True)
class Design:
    """One damper at its design point on the paper's structure (model units).

    kind        'cid', 'pid' or 'tmd'
    mu          mass ratio m/M
    beta        the structure's damping ratio
    gap_ratio   g = d / A_max at the design force (CID, PID)
    e           coefficient of restitution (CID, PID)
    tuning      the PID's r' or the TMD's f: the damper's frequency over the structure's design frequency
    damping     the TMD's damping ratio beta_t, or the PID's pendulum damping ratio (0 in the paper)
    start       where the damper mass starts (CID, PID): centre, left or right
    units       n identical units of mass mu/n each, with the same gap (Bapat and Sankar's multi-unit damper)
    """

    kind: str
    mu: float
    beta: float
    gap_ratio: float = 0.0
    e: float = 0.25
    tuning: float = 1.0
    damping: float = 0.0
    start: str = "centre"
    force_ratio: float = 0.096
    units: int = 1

    def __post_init__(self):
        check_choice("kind", self.kind, DAMPER_KINDS)
        check_fields(self, mu="(0, 10]", beta="(0, 1)", gap_ratio="[0, 1e6]", e="[0, 1]", tuning="[0, 1e4]",
                     damping="[0, 1)", force_ratio="(0, 1e12]")

    @property
    def gap(self) -> float:
        """The physical clearance d, fixed by the design force."""
        return self.gap_ratio * a_max(self.beta, self.force_ratio)


@dataclass(frozen=True)
class Conditions:
    """What changes after the design: the force's scale and the structure's frequency drift."""

    scale: float = 1.0
    drift: float = 0.0

    @property
    def frequency(self) -> float:
        """The structure's natural frequency over its design value."""
        return 1.0 + self.drift


def design_scene(design: Design, r: float, protocol: Protocol, conditions: Conditions = Conditions(),
                 unit_starts=None) -> Scene:
    """One run: the design under ``conditions``, forced at r times the structure's own frequency.

    unit_starts: each unit's initial place between its walls (default: all at the design's start)."""
    w = conditions.frequency
    building = Building.explicit([1.0], [w * w], zeta=design.beta)
    if design.kind == "tmd":
        damper = Damper("tmd", mass=design.mu, tuning=design.tuning / w, damping=design.damping)
    else:
        damper = Damper(design.kind, mass=design.mu, gap=design.gap, e=design.e,
                        tuning=design.tuning / w if design.kind == "pid" else 0.0, damping=design.damping,
                        units=design.units)
    period = 2.0 * math.pi / w
    return Scene(building, (damper,), Harmonic(conditions.scale * design.force_ratio, r * w, 0.0),
                 duration=protocol.periods * period, window=protocol.average_from * period,
                 start=design.start if design.kind != "tmd" else "centre",
                 unit_starts=None if unit_starts is None else tuple(unit_starts))


def bare_amplitude(design: Design, conditions: Conditions = Conditions()) -> float:
    """A_max of the structure under ``conditions``: (F0/K) / (2 beta) with K = (1 + delta)^2."""
    return a_max(design.beta, conditions.scale * design.force_ratio) / conditions.frequency ** 2


def paper_system(design: Design, conditions: Conditions = Conditions()) -> System:
    """The undamped CID or PID under ``conditions`` as the paper's System, by exact similarity.

    In the drifted structure's own time (t' = (1 + delta) t) and the same lengths, the motion is the design's
    with the force F s / (1 + delta)^2, the same clearance d and the pendulum's frequency r' / (1 + delta).
    """
    if design.kind == "tmd" or design.damping != 0.0:
        raise ValueError("the paper's system has no TMD and no pendulum damping")
    w = conditions.frequency
    return System(design.kind, mu=design.mu, beta=design.beta, e=design.e, gap=design.gap,
                  rp=design.tuning / w if design.kind == "pid" else 0.0,
                  force_ratio=conditions.scale * design.force_ratio / (w * w))


def has_paper_form(design: Design) -> bool:
    """Whether the design is one undamped CID or PID unit: the paper's system (:func:`paper_system`), which the
    engine runs on its fast loop."""
    return design.kind != "tmd" and design.damping == 0.0 and design.units == 1


def peak_response(design: Design, r_grid, protocol: Protocol, conditions: Conditions = Conditions()) -> dict:
    """X_m over the frequency grid and its frequency; for a design without the paper's form also the damper's
    stroke (the largest over the grid, and at X_m).  A design with the paper's form (:func:`has_paper_form`) is
    described as the paper's system in the drifted structure's own time (:func:`paper_system`), and asks for
    the amplitude alone: the engine runs it on its paper loop, five to ten times faster, which measures no
    stroke; :func:`scene_peak_response` measures it."""
    r_grid = np.asarray(r_grid, dtype=float)
    if has_paper_form(design):
        system = paper_system(design, conditions)
        start = replace(protocol, start=design.start)
        ratios = np.array([simulate(paper_scene_from_system(system, float(r), start)).amplitude / system.a_max
                           for r in r_grid])
        i = int(np.argmax(ratios))
        return {"X_m": float(ratios[i]), "r_at_max": float(r_grid[i])}
    return scene_peak_response(design, r_grid, protocol, conditions)


def scene_peak_response(design: Design, r_grid, protocol: Protocol, conditions: Conditions = Conditions(),
                        unit_starts=None) -> dict:
    """:func:`peak_response` on the scene core, for any damper, with its stroke."""
    amps, strokes = [], []
    for r in np.asarray(r_grid, dtype=float):
        result = simulate(design_scene(design, float(r), protocol, conditions, unit_starts),
                          measures=("amplitude", "peaks"))
        amps.append(result.amplitude)
        strokes.append(float(np.max(result.peak_strokes)))
    amps, strokes = np.array(amps), np.array(strokes)
    i = int(np.argmax(amps))
    return {"X_m": float(amps[i] / bare_amplitude(design, conditions)), "r_at_max": float(r_grid[i]),
            "stroke_at_max": float(strokes[i]), "stroke_max": float(np.max(strokes))}


def within_band(x, xm, design_value: float, at: float, band: float = BAND) -> tuple[float, float]:
    """The contiguous range of x around ``at`` over which X_m stays within ``band`` of its design value.

    Returns the grid's end points of that range (a range that reaches the grid's end is open there).
    """
    x, ok = np.asarray(x, dtype=float), np.abs(np.asarray(xm, dtype=float) / design_value - 1.0) <= band
    i = int(np.argmin(np.abs(x - at)))
    if not ok[i]:
        return math.nan, math.nan
    lo = hi = i
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    while hi + 1 < x.size and ok[hi + 1]:
        hi += 1
    return float(x[lo]), float(x[hi])


def sensitivity(design: Design, r_grid, protocol: Protocol, *, scales=(), drifts=(), dampings=(),
                restitutions=()) -> dict:
    """X_m (and stroke) along each requested variation; each list is swept alone, the rest as designed."""
    out = {}
    out["scale"] = [peak_response(design, r_grid, protocol, Conditions(scale=s)) for s in scales]
    out["drift"] = [peak_response(design, r_grid, protocol, Conditions(drift=d)) for d in drifts]
    out["damping"] = [peak_response(replace(design, damping=z), r_grid, protocol) for z in dampings]
    out["e"] = [peak_response(replace(design, e=e), r_grid, protocol) for e in restitutions]
    return out


def capped_tmd_damping(design: Design, r_grid, protocol: Protocol, stroke_cap: float, *, tol: float = 1e-3,
                       beta_t_max: float = 0.9, at: dict | None = None) -> tuple[float, dict]:
    """The smallest beta_t (from the design's up) whose largest stroke over the grid is within ``stroke_cap``.

    Bisection on beta_t: a TMD's stroke falls as its damping rises.  ``at``: the design's own peak response,
    if already run.  Returns (beta_t, its peak response).
    """
    if design.kind != "tmd":
        raise ValueError("only a TMD's stroke is capped by raising its damping")
    lo, hi = design.damping, beta_t_max
    at = at or peak_response(design, r_grid, protocol)
    if at["stroke_max"] <= stroke_cap:
        return lo, at
    top = peak_response(replace(design, damping=hi), r_grid, protocol)
    if top["stroke_max"] > stroke_cap:
        raise ValueError(f"no beta_t up to {beta_t_max} keeps the TMD's stroke within {stroke_cap}")
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        res = peak_response(replace(design, damping=mid), r_grid, protocol)
        lo, hi, top = (mid, hi, top) if res["stroke_max"] > stroke_cap else (lo, mid, res)
    return hi, top


# ----------------------------------------------------------------------------
# the stage's products: one dataset per design, Table 1 in numbers
# ----------------------------------------------------------------------------

# each variation: its dimension, long name, and how a design is changed along it
VARIATIONS = {
    "scale": ("force amplitude over the design's (the physical gap as designed)", "1"),
    "drift": ("relative drift of the structure's natural frequency (the damper as designed)", "1"),
    "damping": ("damping ratio of the damper (TMD beta_t, PID pendulum)", "1"),
    "e": ("coefficient of restitution", "1"),
}
MEASURES = {
    "X_m": ("amplitude ratio X_m: the largest protocol amplitude over the frequency grid over A_max", "1"),
    "r_at_max": ("forcing frequency of X_m over the structure's own natural frequency", "1"),
    "stroke_max": ("largest displacement of the damper mass relative to the structure, over the grid's runs",
                   "1"),
}


def applicable(kind: str) -> tuple[str, ...]:
    """The variations that change a damper of this kind: no damping in a CID, no restitution in a TMD."""
    return {"cid": ("scale", "drift", "e"), "pid": ("scale", "drift", "damping", "e"),
            "tmd": ("scale", "drift", "damping")}[kind]


def design_dataset(design: Design, grids: dict, r_grid, protocol: Protocol, stroke_cap: float | None = None):
    """X_m, its frequency and the stroke at the design point and along each applicable variation.

    grids: variation name -> values (scale, drift, damping, e); the ones that do not apply are left out.
    stroke_cap (TMD only): also the smallest beta_t that keeps its stroke within it, and X_m then.
    """
    import xarray as xr

    wanted = {name: np.asarray(grids[name], dtype=float) for name in applicable(design.kind) if name in grids}
    sweeps = sensitivity(design, r_grid, protocol, scales=wanted.get("scale", ()), drifts=wanted.get("drift", ()),
                         dampings=wanted.get("damping", ()), restitutions=wanted.get("e", ()))
    # the stroke needs the scene loop, so the design point always runs there (Table 1, row 5); a design with
    # the paper's form takes its X_m from the paper loop, as along its variations
    on_scene = scene_peak_response(design, r_grid, protocol)
    design_point = {**on_scene, **peak_response(design, r_grid, protocol)} if has_paper_form(design) else on_scene
    data = {f"{m}_design": ((), design_point[m], {"long_name": f"{text}, at the design point", "units": u})
            for m, (text, u) in MEASURES.items()}
    coords = {}
    for name, values in wanted.items():
        text, units = VARIATIONS[name]
        coords[name] = (name, values, {"long_name": text, "units": units})
        for m, (mtext, u) in MEASURES.items():
            if all(m in run for run in sweeps[name]):
                data[f"{m}_vs_{name}"] = (name, [run[m] for run in sweeps[name]], {"long_name": mtext, "units": u})
    if stroke_cap is not None:
        beta_t, capped = capped_tmd_damping(design, r_grid, protocol, stroke_cap, at=on_scene)
        data["stroke_cap"] = ((), stroke_cap, {"long_name": "the stroke the TMD is held to: half a CID's gap",
                                               "units": "1"})
        data["damping_capped"] = ((), beta_t, {"long_name": "smallest TMD damping ratio whose stroke fits the cap",
                                               "units": "1"})
        data["X_m_capped"] = ((), capped["X_m"], {"long_name": "X_m of the TMD with its stroke capped",
                                                  "units": "1"})
    ds = xr.Dataset(data, coords=coords)
    if design.kind != "tmd" and grids.get("units"):
        add_multi_unit(ds, design, grids["units"], r_grid, protocol, grids["members"], grids["seed"],
                       single=on_scene)
    ds.attrs.update({"title": f"Table 1 in numbers: design {design.kind}", "kind": design.kind,
                     "design": str(design.__dict__),
                     "a_max": a_max(design.beta, design.force_ratio), "periods": protocol.periods,
                     "average_from": protocol.average_from, "initial_condition": f"structure at rest, damper mass "
                     f"{'centred' if design.kind == 'tmd' else 'at start ' + design.start}",
                     "length_unit": "the paper's model unit (F0/K = force_ratio at the design force)"})
    return ds


def max_change(ds, name: str) -> float:
    """The largest relative change of X_m from its design value along one variation (NaN: not varied)."""
    key = f"X_m_vs_{name}"
    if key not in ds:
        return math.nan
    return float(np.max(np.abs(ds[key].values / float(ds["X_m_design"]) - 1.0)))


# Table 1 of the paper: its row, characteristic and words for the CID, PID and TMD ("not rated": its "~ . ~")
TABLE1 = [
    (2, "effectiveness for steady-state motion", ("moderate", "moderate", "high")),
    (5, "space requirement", ("moderate", "moderate", "high")),
    (6, "sensitivity to tuning", ("not rated", "low", "high")),
    (7, "sensitivity to damping of the damper", ("not rated", "not rated", "high")),
    (9, "sensitivity to amplitude of the excitation", ("high", "moderate", "low")),
    (10, "material dependence (coefficient of restitution)", ("moderate", "moderate", "moderate")),
]
WORD_RANK = {"low": 0, "moderate": 1, "high": 2}
_NUMBERS = {
    2: ("1 / X_m at the design point", lambda ds: 1.0 / float(ds["X_m_design"])),
    5: ("largest stroke over A_max", lambda ds: float(ds["stroke_max_design"]) / float(ds.attrs["a_max"])),
    6: ("largest relative change of X_m over the drifts", lambda ds: max_change(ds, "drift")),
    7: ("largest relative change of X_m over the damping ratios", lambda ds: max_change(ds, "damping")),
    9: ("largest relative change of X_m over the force scales", lambda ds: max_change(ds, "scale")),
    10: ("largest relative change of X_m over e", lambda ds: max_change(ds, "e")),
}


def _supports(rank: int | None, number: float, others: list[tuple[int | None, float]]) -> str:
    """Does the number order like the word against every other damper's (higher word, larger number)?"""
    if rank is None or not math.isfinite(number):
        return "not judged"
    ordered = [(r, n) for r, n in others if r is not None and math.isfinite(n) and r != rank]
    if not ordered:
        return "not judged"
    ok = all((n < number) if r < rank else (n > number) for r, n in ordered)
    return "yes" if ok else "no"


def table1_measured(designs: dict) -> pd.DataFrame:
    """One row per Table 1 characteristic we compute and per design: the paper's word, our number, support.

    designs: design name -> its dataset.  A number 'supports' the word when it orders against every other
    damper's number as the words order (low < moderate < high; a larger number is more of the
    characteristic; effectiveness is 1/X_m), for every design of a damper with a different word.
    """
    column = {"cid": 0, "pid": 1, "tmd": 2}
    rows = []
    for row, characteristic, words in TABLE1:
        what, number = _NUMBERS[row]
        entries = []
        for name, ds in designs.items():
            word = words[column[ds.attrs["kind"]]]
            entries.append((name, ds.attrs["kind"], word, WORD_RANK.get(word), number(ds)))
        for name, kind, word, rank, value in entries:
            others = [(r, v) for n, k, _, r, v in entries if k != kind]
            ds = designs[name]
            lo, hi = _band(ds, row)
            rows.append({"row": row, "characteristic": characteristic, "design": name, "damper": kind.upper(),
                         "paper_word": word, "measure": what, "number": value,
                         "supports": _supports(rank, value, others), "band_lo": lo, "band_hi": hi,
                         "note": _note(ds, row)})
    rows += [_multi_unit_row(name, ds) for name, ds in designs.items() if "X_m_units_symmetric" in ds]
    return pd.DataFrame(rows)


def _multi_unit_row(name: str, ds) -> dict:
    change, holds = same_level(ds)
    n = ds["units"].values
    return {"row": 5, "characteristic": f"space: {n.max()} units instead of one (Ref. 14: up to 9 units give "
            "the same level of performance)", "design": name, "damper": ds.attrs["kind"].upper(),
            "paper_word": "same level", "measure": "largest relative change of X_m from one unit, each start "
            f"(same, staggered, ensemble median) against its own one-unit value, n = {', '.join(map(str, n))}",
            "number": change, "supports": {True: "yes", False: "no", None: "not judged"}[holds],
            "band_lo": math.nan, "band_hi": math.nan,
            "note": _multi_unit_note(ds, holds)}


def _multi_unit_note(ds, holds: bool | None) -> str:
    undefined = [int(n) for n, ok in zip(ds["units"].values, _all_defined(ds)) if not ok]
    if not undefined:
        return f"'same level' read as within {SAME_LEVEL:.0%}"
    capped = (f"X_m undefined for n = {', '.join(map(str, undefined))}: a run of the split damper stopped at "
              "the event cap (the units' grazing contacts accumulate)")
    if holds is False:
        return f"{capped}; the defined n already move X_m beyond {SAME_LEVEL:.0%}, which refutes the claim"
    return f"{capped}, so the claim is not judged"


def _all_defined(ds) -> np.ndarray:
    """Per number of units: whether every X_m of it (together, staggered, every ensemble member) is defined."""
    return (np.isfinite(ds["X_m_units_symmetric"].values) & np.isfinite(ds["X_m_units_staggered"].values)
            & np.all(np.isfinite(ds["X_m_units_ensemble"].values), axis=1))


def _band(ds, row: int) -> tuple[float, float]:
    """Rows 6 and 9: the range of drift or scale over which X_m stays within 25 % of its design value."""
    name, at = {6: ("drift", 0.0), 9: ("scale", 1.0)}.get(row, (None, None))
    if name is None or f"X_m_vs_{name}" not in ds:
        return math.nan, math.nan
    return within_band(ds[name].values, ds[f"X_m_vs_{name}"].values, float(ds["X_m_design"]), at)


def _note(ds, row: int) -> str:
    kind = ds.attrs["kind"]
    if row == 7 and kind == "cid":
        return (f"a CID has no damper damping; its dissipation is set by e instead, and X_m changes by up to "
                f"{max_change(ds, 'e'):.0%} over e = 0 to 1 (row 10)")
    if row == 5 and "X_m_capped" in ds:
        return (f"stroke capped to the CID's half gap {float(ds['stroke_cap']):.3g}: beta_t "
                f"{float(ds['damping_capped']):.3g}, X_m {float(ds['X_m_capped']):.3f} (uncapped "
                f"{float(ds['X_m_design']):.3f})")
    if row == 5 and kind != "tmd":
        return "bounded by half the gap: the mass travels between the walls"
    if row == 10 and kind == "tmd":
        return "a TMD has no impacts: nothing in it depends on e"
    return ""


# ----------------------------------------------------------------------------
# the design points, from the study's own sweeps and TMD optimum
# ----------------------------------------------------------------------------


def design_names(cfg: dict) -> list[str]:
    """The designs of the configuration: the CID from each start, the PID per tuning and start, the TMD."""
    rb, starts = cfg["robustness"], cfg["protocol"]["starts"]
    names = [f"cid_{s}" for s in starts["cid"]]
    names += [f"pid_rp{rp:g}_{s}" for rp in rb["pid_tunings"] for s in starts["pid"]]
    return names + ["tmd"]


def designs_from_study(cfg: dict, optima: dict, tmd: dict) -> dict:
    """Each design at its optimum: ``optima`` maps 'cid' and 'pid_rp<r'>' to (start -> optimum g), from the
    sweeps; ``tmd`` is the equal-peak optimum (f, beta_t).  Returns name -> Design fields (JSON-ready)."""
    rb, beta, f0 = cfg["robustness"], cfg["structure"]["beta"], cfg["structure"]["force_ratio"]
    out = {}
    for name in design_names(cfg):
        if name == "tmd":
            design = Design("tmd", rb["mu"], beta, tuning=tmd["f"], damping=tmd["beta_t"], force_ratio=f0)
        else:
            kind, *tag, start = name.split("_")
            rp = float(tag[0][2:]) if kind == "pid" else 0.0
            g = optima[kind if kind == "cid" else tag[0]][start]
            if not math.isfinite(g):
                raise ValueError(f"design {name}: its sweep has no optimum gap (every X_m is NaN)")
            design = Design(kind, rb["mu"], beta, gap_ratio=g, e=rb["e"], tuning=rp if kind == "pid" else 1.0,
                            start=start, force_ratio=f0)
        out[name] = dict(design.__dict__)
    return out


def stroke_cap(designs: dict) -> float:
    """What the TMD's stroke is held to: half the smallest CID design's gap (the CID's space, as designed)."""
    cids = [Design(**d) for d in designs.values() if d["kind"] == "cid"]
    if not cids:
        raise ValueError("no CID design to take the gap from")
    return 0.5 * min(cids, key=lambda d: d.gap_ratio).gap


def grids(cfg: dict, tmd_beta_t: float) -> dict:
    """The variations' values (log grids for the force scale and the damping, linear ones for drift and e),
    and the multi-unit split: its numbers of units, ensemble size and seed."""
    rb = cfg["robustness"]
    if 1 not in rb["units"]:
        raise ValueError("robustness.units must include 1: the single unit every split is compared with")

    def log_grid(spec):
        return np.geomspace(spec["min"], spec["max"], spec["n"])

    e = rb["restitution"]
    return {"units": list(rb["units"]), "members": rb["ensemble"]["members"], "seed": rb["ensemble"]["seed"],
            "scale": log_grid(rb["scales"]), "drift": np.linspace(rb["drifts"]["min"], rb["drifts"]["max"],
                                                                  rb["drifts"]["n"]),
            "damping": tmd_beta_t * log_grid(rb["damping_factors"]),
            "e": np.round(np.arange(e["min"], e["max"] + 0.5 * e["step"], e["step"]), 10)}


def optima_from_sweeps(datasets) -> dict:
    """'cid' or 'rp<r'>' -> (start -> optimum gap ratio), from sweep datasets (their 'curve' attribute)."""
    import json


    out = {}
    for ds in datasets:
        spec = json.loads(ds.attrs["curve"])
        key = "cid" if spec["damper"] == "cid" else f"rp{spec['rp']:g}"
        out[key] = {str(s): optimum(ds, str(s))[0] for s in ds["start"].values}
    return out



# ----------------------------------------------------------------------------
# several units (Ref. 14 of the paper: up to 9 units perform as one)
# ----------------------------------------------------------------------------

SAME_LEVEL = 0.10   # "the same level of performance": X_m within 10 % of the single unit's


def staggered_starts(n: int, gap: float) -> np.ndarray:
    """n units spread evenly over the clearance, from one wall to the other."""
    return np.linspace(-0.5 * gap, 0.5 * gap, n)


def random_starts(n: int, gap: float, seed: int, member: int) -> np.ndarray:
    """n units at seeded uniform places between their walls (one ensemble member)."""
    return np.random.default_rng([seed, n, member]).uniform(-0.5 * gap, 0.5 * gap, n)


def multi_unit(design: Design, units, r_grid, protocol: Protocol, members: int, seed: int,
               single: dict | None = None) -> dict:
    """X_m of the design split into n units of the same total mass and gap, for each n in ``units``.

    'symmetric': every unit at the design's start (identical units that start together move as one);
    'staggered': the units spread evenly from wall to wall; 'ensemble': ``members`` seeded random starts.
    ``single``: the one unit's scene response at the design's start, if already run (both n = 1 rows).
    """
    if design.kind == "tmd":
        raise ValueError("the multi-unit rows are the impact dampers'")
    out = {"symmetric": [], "staggered": [], "ensemble": []}
    for n in units:
        split = replace(design, units=int(n))
        if n == 1:  # one unit: the design itself, wherever 'staggered' would spread it
            single = single or scene_peak_response(split, r_grid, protocol)
            out["symmetric"].append(single["X_m"])
            out["staggered"].append(single["X_m"])
        else:
            out["symmetric"].append(scene_peak_response(split, r_grid, protocol)["X_m"])
            out["staggered"].append(scene_peak_response(split, r_grid, protocol,
                                                        unit_starts=staggered_starts(n, design.gap))["X_m"])
        out["ensemble"].append([scene_peak_response(split, r_grid, protocol,
                                                    unit_starts=random_starts(n, design.gap, seed, m))["X_m"]
                                for m in range(members)])
    return out


def add_multi_unit(ds, design: Design, units, r_grid, protocol: Protocol, members: int, seed: int,
                   single: dict | None = None) -> None:
    """The multi-unit rows as variables over ``units`` (and ``member`` for the ensemble)."""
    rows = multi_unit(design, units, r_grid, protocol, members, seed, single)
    ds.coords["units"] = ("units", np.asarray(units, dtype=np.int64), {
        "long_name": "number of identical units (same total mass and gap)", "units": "1"})
    ds.coords["member"] = ("member", np.arange(members), {"long_name": "ensemble member (seeded starts)",
                                                           "units": "1"})
    ds["X_m_units_symmetric"] = ("units", rows["symmetric"], {
        "long_name": "X_m with every unit at the design's start", "units": "1"})
    ds["X_m_units_staggered"] = ("units", rows["staggered"], {
        "long_name": "X_m with the units spread evenly from wall to wall", "units": "1"})
    ds["X_m_units_ensemble"] = (("units", "member"), rows["ensemble"], {
        "long_name": "X_m with the units at seeded random places between their walls", "units": "1"})
    ds.attrs["ensemble_seed"] = seed


def same_level(ds) -> tuple[float, bool | None]:
    """The largest relative change of X_m from one unit to n, each kind of start against its own single-unit
    value (the ensemble by its median), and whether it stays within SAME_LEVEL.

    Where some X_m is undefined (a run of the split damper stopped at the event cap), the claim is still
    refuted by any defined change beyond SAME_LEVEL (it is a claim about every n up to 9); otherwise the
    verdict is withheld: (largest defined change or NaN, None).
    """
    curves = [ds["X_m_units_symmetric"].values, ds["X_m_units_staggered"].values,
              np.median(ds["X_m_units_ensemble"].values, axis=1)]
    one = list(ds["units"].values).index(1)
    changes = np.concatenate([np.abs(c / c[one] - 1.0) for c in curves])
    defined = changes[np.isfinite(changes)]
    change = float(np.max(defined)) if defined.size else math.nan
    if defined.size < changes.size:
        return (change, False) if change > SAME_LEVEL else (change, None)
    return change, change <= SAME_LEVEL
