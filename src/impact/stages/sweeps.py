"""The parametric study as configuration: curves, grids and one curve's sweeps.

A curve is a damper configuration (type, mu, e, r', nu) swept over the gap-ratio
grid and the frequency grid for every configured start.  Curves are named by
their parameters, so a curve drawn in several figures (the CID with mu = 0.01,
e = 0.25 is in Figs. 8, 9 and 11) is one file, computed once.
"""

from __future__ import annotations

import math

import numpy as np

from impact.engine.run import sweep
from impact.model.kinds import either, kind_of, kinds_with
from impact.model.params import ParameterError, Protocol, System, curve_id, frequency_grid
from impact.outputs.datasets import curve_dataset
from impact.stages.readings import add_readings


def friction_scale(cfg: dict, spec: dict) -> dict:
    """Structure frequency and length unit that set a curve's friction (curve keys override config)."""
    base = cfg.get("friction", {})
    return {key: spec.get(key, base.get(key, default))
            for key, default in (("frequency_hz", 1.5), ("unit_m", 0.01))}


def figure_curves(cfg: dict, figure: str) -> dict:
    """Curves of one figure, id -> spec, in drawing order."""
    out = {}
    for panel in cfg["figures"][figure]["panels"]:
        for spec in panel["curves"]:
            out.setdefault(curve_id(spec), spec)
    return out


def all_curves(cfg: dict) -> dict:
    """Every curve the study sweeps: those drawn in figures and those of the coexistence stage."""
    out = {}
    for fig in cfg["figures"]:
        out.update(figure_curves(cfg, fig))
    for spec in cfg.get("coexistence", {}).get("curves", []):
        out.setdefault(curve_id(spec), spec)
    return out


def gap_grid(cfg: dict) -> np.ndarray:
    g = cfg["protocol"]["gap"]
    return frequency_grid(g["min"], g["max"], g["step"])


def freq_grid(cfg: dict) -> np.ndarray:
    f = cfg["protocol"]["freq"]
    return frequency_grid(f["min"], f["max"], f["step"])


def non_finite_keys(node, where: str = "") -> list:
    """The keys of a configuration holding NaN or an infinity (YAML's .nan, .inf), which a JSON schema's bounds
    let through: every comparison with NaN is false."""
    if isinstance(node, dict):
        return [k for key, value in node.items() for k in non_finite_keys(value, f"{where}.{key}" if where else key)]
    if isinstance(node, list):
        return [k for i, value in enumerate(node) for k in non_finite_keys(value, f"{where}[{i}]")]
    return [where] if isinstance(node, float) and not math.isfinite(node) else []


def check_config(cfg: dict) -> None:
    """Checks a JSON schema cannot express; the message names the key."""
    bad = non_finite_keys(cfg)
    if bad:
        raise ParameterError(f"{bad[0]} = {_at(cfg, bad[0])}: a finite number is needed"
                             + (f" (and at {', '.join(bad[1:])})" if bad[1:] else ""))
    proto = cfg["protocol"]
    if proto["average_from"] >= proto["periods"]:
        raise ParameterError(f"protocol.average_from = {proto['average_from']} must be below "
                             f"protocol.periods = {proto['periods']}")
    for grid in ("freq", "gap"):
        if proto[grid]["max"] < proto[grid]["min"]:
            raise ParameterError(f"protocol.{grid}.max = {proto[grid]['max']} is below protocol.{grid}.min")
    for fig, fcfg in cfg["figures"].items():
        for i, panel in enumerate(fcfg["panels"]):
            for j, spec in enumerate(panel["curves"]):
                where = f"figures.{fig}.panels[{i}].curves[{j}]"
                try:
                    curve_system(cfg, spec, 1.0)
                except ParameterError as exc:
                    raise ParameterError(f"{where}: {exc}") from None


def _at(cfg: dict, where: str):
    """The value at a key path of non_finite_keys's form (a.b[2].c)."""
    node = cfg
    for part in where.replace("[", ".[").split("."):
        node = node[int(part[1:-1])] if part.startswith("[") else node[part]
    return node


def curve_system(cfg: dict, spec: dict, gap_ratio: float) -> System:
    structure = cfg["structure"]
    kw = dict(rp=spec.get("rp", 0.0), force_ratio=structure["force_ratio"], phase=cfg["protocol"].get("phase", 0.0))
    if spec.get("nu", 0.0):
        kw.update(nu=spec["nu"], **friction_scale(cfg, spec))
    if "rp" in spec and not kind_of(spec["damper"]).spring:
        raise ParameterError(f"rp is only for a damper with a spring ({either(kinds_with('spring'))})")
    return System.from_gap_ratio(spec["damper"], mu=spec["mu"], beta=structure["beta"], e=spec["e"],
                                 gap_ratio=gap_ratio, **kw)


def curve_starts(cfg: dict, spec: dict) -> list:
    return list(cfg["protocol"]["starts"][spec["damper"]])


def run_curve(cfg: dict, spec: dict, gap_ratios=None, mode: str = "from_rest"):
    """All sweeps of one curve (one sweep mode), as a self-describing dataset."""
    gaps = gap_grid(cfg) if gap_ratios is None else np.asarray(gap_ratios, dtype=float)
    r = freq_grid(cfg)
    proto_cfg = cfg["protocol"]
    starts = curve_starts(cfg, spec)
    systems = [curve_system(cfg, spec, float(g)) for g in gaps]
    protocols = [Protocol(periods=proto_cfg["periods"], average_from=proto_cfg["average_from"], start=start)
                 for start in starts]
    results = [[sweep(system, r, protocol, mode=mode) for system in systems] for protocol in protocols]
    ds = curve_dataset(systems[0], gaps, starts, results, protocols[-1], curve={"id": curve_id(spec), **spec},
                       config=cfg, sweep_mode=mode)
    if mode == "from_rest":  # the readings are of runs from rest; a continuation's are another measure
        add_readings(ds, systems, protocols)
    return ds
