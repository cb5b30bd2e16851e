"""The robustness stage's designs: what a design is, the conditions it meets, and the design points
taken from the study's own sweeps and TMD optimum.  Plain data: nothing here runs the engine, so the
workflow's start-up and the collectors read it without loading numba."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np

from impact.model.kinds import CID, KINDS, PID, TMD, damper_kinds
from impact.model.params import MAX_TUNING, a_max, check_choice, check_fields
from impact.outputs.datasets import optimum
from impact.stages.curves import curve_specs

BAND = 0.25   # "X_m stays within 25 % of its design value"


@dataclass(frozen=True)
class Design:
    """One damper at its design point on the paper's structure (model units).

    kind        a damper kind (model.kinds): the study designs the CID, the PID and the TMD
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
        check_choice("kind", self.kind, damper_kinds())  # read now: a kind registered later is a kind
        check_fields(self, mu="(0, 10]", beta="(0, 1)", gap_ratio="[0, 1e6]", e="[0, 1]",
                     tuning=f"[0, {MAX_TUNING:g}]", damping="[0, 1)", force_ratio="(0, 1e12]")

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


def bare_amplitude(design: Design, conditions: Conditions = Conditions()) -> float:
    """A_max of the structure under ``conditions``: (F0/K) / (2 beta) with K = (1 + delta)^2."""
    return a_max(design.beta, conditions.scale * design.force_ratio) / conditions.frequency ** 2


def has_paper_form(design: Design) -> bool:
    """Whether the design is one undamped CID or PID unit: the paper's system (:func:`paper_system`), which the
    engine runs on its fast loop."""
    return KINDS[design.kind].paper and design.damping == 0.0 and design.units == 1


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
    """The variations that change a damper of this kind: its damping if it has a dashpot (not the CID), its
    restitution if it has walls (not the TMD); the force's scale and the structure's drift change every kind."""
    parts = KINDS[kind]
    return ("scale", "drift") + ("damping",) * parts.dashpot + ("e",) * parts.walls


def design_names(cfg: dict) -> list[str]:
    """The designs of the configuration: the CID from each start, the PID per tuning and start, the TMD."""
    rb, starts = cfg["robustness"], cfg["protocol"]["starts"]
    names = [f"{CID}_{s}" for s in starts[CID]]
    names += [f"{PID}_rp{rp:g}_{s}" for rp in rb["pid_tunings"] for s in starts[PID]]
    return names + [TMD]


def design_curves(cfg: dict) -> list[dict]:
    """The sweep curves whose optimum gaps are the impact dampers' design points: the CID's and the PID's at
    each tuning, of the robustness section's mass ratio and restitution."""
    rb = cfg["robustness"]
    return curve_specs((CID, PID), (rb["mu"],), (rb["e"],), rb["pid_tunings"])


def designs_from_study(cfg: dict, optima: dict, tmd: dict) -> dict:
    """Each design at its optimum: ``optima`` maps the CID and 'rp<r'>' (a PID's tuning) to (start -> optimum g), from the
    sweeps; ``tmd`` is the equal-peak optimum (f, beta_t).  Returns name -> Design fields (JSON-ready)."""
    rb, beta, f0 = cfg["robustness"], cfg["structure"]["beta"], cfg["structure"]["force_ratio"]
    out = {}
    for name in design_names(cfg):
        if name == TMD:
            design = Design(TMD, rb["mu"], beta, tuning=tmd["f"], damping=tmd["beta_t"], force_ratio=f0)
        else:
            kind, *tag, start = name.split("_")
            rp = float(tag[0][2:]) if KINDS[kind].spring else 0.0
            g = optima[tag[0] if tag else kind][start]
            if not math.isfinite(g):
                raise ValueError(f"design {name}: its sweep has no optimum gap (every X_m is NaN)")
            design = Design(kind, rb["mu"], beta, gap_ratio=g, e=rb["e"], tuning=rp if KINDS[kind].spring else 1.0,
                            start=start, force_ratio=f0)
        out[name] = dict(design.__dict__)
    return out


def stroke_cap(designs: dict) -> float:
    """What the TMD's stroke is held to: half the smallest CID design's gap (the CID's space, as designed)."""
    cids = [Design(**d) for d in designs.values() if d["kind"] == CID]
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
    """The CID or 'rp<r'>' (a PID's tuning) -> (start -> optimum gap ratio), from sweep datasets (their 'curve'
    attribute)."""

    out = {}
    for ds in datasets:
        spec = json.loads(ds.attrs["curve"])
        key = f"rp{spec['rp']:g}" if KINDS[spec["damper"]].spring else spec["damper"]
        out[key] = {str(s): optimum(ds, str(s))[0] for s in ds["start"].values}
    return out


SAME_LEVEL = 0.10   # "the same level of performance": X_m within 10 % of the single unit's


def staggered_starts(n: int, gap: float) -> np.ndarray:
    """n units spread evenly over the clearance, from one wall to the other."""
    return np.linspace(-0.5 * gap, 0.5 * gap, n)


def random_starts(n: int, gap: float, seed: int, member: int) -> np.ndarray:
    """n units at seeded uniform places between their walls (one ensemble member)."""
    return np.random.default_rng([seed, n, member]).uniform(-0.5 * gap, 0.5 * gap, n)
