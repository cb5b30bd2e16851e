"""The cross-validation's grid of cases on the virtual rig (whose configuration is :mod:`impact.rig.config`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np

from impact.rig.config import validation_config


def frequency_values(freq: dict, extra: Iterable[float] = ()) -> np.ndarray:
    """The sweep grid min, min + step, ..., max (rounded), plus ``extra`` values, sorted."""
    n = int(math.floor((freq["max"] - freq["min"]) / freq["step"] + 1e-9)) + 1
    grid = np.round(freq["min"] + freq["step"] * np.arange(n), 10)
    return np.unique(np.concatenate([grid, np.round(np.asarray(list(extra), dtype=float), 10)]))


@dataclass(frozen=True)
class Case:
    """One configuration of the experimental grid."""

    mu: float
    gap_mm: float
    rp: float
    wall: str

    @property
    def setup(self) -> str:
        """The ball, clearance and tuning, which every wall of the grid repeats."""
        return f"mu{self.mu:g}_d{self.gap_mm:g}_rp{self.rp:g}"

    @property
    def id(self) -> str:
        return f"{self.setup}_{self.wall}"

    @classmethod
    def of(cls, obj) -> "Case":
        if isinstance(obj, Case):
            return obj
        if isinstance(obj, str):
            for c in all_cases(None):
                if c.id == obj:
                    return c
            raise ValueError(f"unknown case id {obj!r}")
        return cls(float(obj["mu"]), float(obj["gap_mm"]), float(obj["rp"]), str(obj["wall"]))


def all_cases(cfg: dict | None) -> list[Case]:
    """The grid mu x d x r' x wall of the configuration (108 cases by default)."""
    g = validation_config(cfg)["grid"]
    return [Case(mu, d, rp, w) for mu in g["mu"] for d in g["gap_mm"] for rp in g["rp"] for w in g["walls"]]


def study_cases(cfg: dict, smoke: bool) -> list[Case]:
    """The cases a run covers: the smoke subset, or the whole grid."""
    return [Case.of(c) for c in cfg["smoke"]["cases"]] if smoke else all_cases(cfg)


def batches(cases: list[Case]) -> tuple[list[str], list[str]]:
    """(walls, setups) of the cases, which the workflow runs as one job per wall, each job every setup on its
    wall: so the cases must be every setup on every wall (the grid is; a smoke subset must be one too)."""
    walls = list(dict.fromkeys(c.wall for c in cases))
    setups = list(dict.fromkeys(c.setup for c in cases))
    missing = sorted({f"{s}_{w}" for s in setups for w in walls} - {c.id for c in cases})
    if missing:
        raise ValueError(f"validation cases: the workflow runs one job per wall with every setup (ball, gap, r') "
                         f"on it, so the cases must be every setup on every wall; missing {', '.join(missing)}")
    return walls, setups


def wall_e(cfg: dict, wall: str) -> float:
    return float(cfg["walls"][wall]["e"])
