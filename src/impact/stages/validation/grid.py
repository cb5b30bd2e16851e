"""The synthetic experiment's configuration and its grid of cases.

Every parameter of the virtual rig and of the cross-validation has its default, its description
and its allowed range in one place, ``rig.schema.yaml`` beside this module.  ``validation_config``
fills the defaults in and refuses a bad value naming the key, as Snakemake's ``validate()`` does
with the same schema in the workflow; the checks that relate two keys follow.
"""

from __future__ import annotations

import copy
import functools
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

import jsonschema
import numpy as np
import yaml

SCHEMA_PATH = Path(__file__).with_name("rig.schema.yaml")


@functools.cache
def _validator():

    schema = yaml.safe_load(SCHEMA_PATH.read_text())
    base = jsonschema.Draft202012Validator
    check_properties = base.VALIDATORS["properties"]

    def fill_defaults(validator, properties, instance, subschema):
        if isinstance(instance, dict):
            for key, sub in properties.items():
                if "default" in sub and key not in instance:
                    instance[key] = copy.deepcopy(sub["default"])  # a default is never shared
        yield from check_properties(validator, properties, instance, subschema)

    filling = jsonschema.validators.extend(base, {"properties": fill_defaults})
    return filling(schema)


def validation_config(cfg: dict | None = None, *, smoke: bool = False) -> dict[str, Any]:
    """The rig's whole configuration: ``cfg`` (the keys that differ) with the schema's defaults.

    ``cfg`` may be the file's content with everything under one ``validation`` key.  A value outside
    the schema raises ValueError naming the key and what is allowed.  ``smoke=True`` lays the
    ``smoke`` section over the result (a shortened protocol, for tests and quick runs).
    """
    if cfg and set(cfg) == {"validation"}:
        cfg = cfg["validation"]
    key = _plain_key(cfg, smoke)
    if key is None:
        return _filled(cfg, smoke)
    return copy.deepcopy(_filled_once(key))  # a fresh dict every call: callers may change theirs


def _plain_key(cfg, smoke: bool) -> str | None:
    """``cfg`` as canonical JSON when JSON gives it back unchanged (no tuples, arrays or NaN), else None."""
    try:
        key = json.dumps([cfg or {}, bool(smoke)], sort_keys=True)
    except (TypeError, ValueError):
        return None
    return key if json.loads(key) == [cfg or {}, bool(smoke)] else None


@functools.lru_cache(maxsize=32)
def _filled_once(key: str) -> dict[str, Any]:
    # a rig run fills the same configuration in for every point of a case: validate it once per process
    cfg, smoke = json.loads(key)
    return _filled(cfg, smoke)


def _filled(cfg: dict | None, smoke: bool) -> dict[str, Any]:
    out = copy.deepcopy(dict(cfg or {}))
    if "walls" in out:  # a wall given is laid over the paper's materials: one e can change alone
        out["walls"] = merge(_validator().schema["properties"]["walls"]["default"], out["walls"])
    errors = sorted(_validator().iter_errors(out), key=lambda e: list(e.absolute_path))
    if errors:
        raise ValueError(f"validation config: {_explain(errors[0])}")
    check_config(out)
    if smoke:
        out = merge(out, {k: v for k, v in out["smoke"].items() if k != "cases"})
    return out


def _explain(error) -> str:
    """A schema error as the key it names and what is allowed there."""
    where = ".".join(str(p) for p in error.absolute_path)
    if error.validator == "additionalProperties":
        allowed = sorted(error.schema.get("properties", {}))
        unknown = sorted(set(error.instance) - set(allowed))
        return f"unknown key(s) {unknown} in {where or 'the top level'} (allowed: {allowed})"
    return f"{where or 'the top level'}: {error.message}"


def check_config(cfg: dict) -> None:
    """The checks that relate two keys (ValueError naming them)."""
    balls = cfg["balls"]
    if len(balls["mu"]) != len(balls["diameters_mm"]):
        raise ValueError("validation config: balls.mu and balls.diameters_mm differ in length")
    for mu in cfg["grid"]["mu"]:
        if not any(abs(mu - m) <= 1e-9 for m in balls["mu"]):
            raise ValueError(f"validation config: grid.mu {mu} is not one of balls.mu {balls['mu']}")
    for w in cfg["grid"]["walls"]:
        if w not in cfg["walls"]:
            raise ValueError(f"validation config: grid wall {w!r} is not defined under walls")
    for name in ("protocol", "bare"):
        grid = cfg[name]["freq" if name == "protocol" else "fine_freq"]
        if grid["max"] < grid["min"]:
            raise ValueError(f"validation config: {name} frequency grid: max {grid['max']} < min {grid['min']}")
    pr = cfg["protocol"]
    if not 0 <= pr["average_from"] < pr["periods"]:
        raise ValueError("validation config: protocol.average_from must be in [0, protocol.periods)")


def merge(dst: dict, src: dict) -> dict:
    """``src`` laid over a copy of ``dst``: nested dicts merged, lists and scalars replaced."""
    out = copy.deepcopy(dst)
    for key, val in src.items():
        if isinstance(val, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], val)
        else:
            out[key] = copy.deepcopy(val)
    return out


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
