"""The virtual rig's configuration: its schema's defaults filled in, a bad value refused by name.

Every parameter of the virtual rig and of the cross-validation run on it has its default, its description
and its allowed range in one place, ``rig.schema.yaml`` beside this module.  ``validation_config``
fills the defaults in and refuses a bad value naming the key, as Snakemake's ``validate()`` does
with the same schema in the workflow; the checks that relate two keys follow.
"""

from __future__ import annotations

import copy
import functools
import json
from pathlib import Path
from typing import Any

import jsonschema
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
