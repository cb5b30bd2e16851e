"""The incremental dynamic analysis's runs on the exact engine: per building, the bare building (with every ground
motion's Sa(T1)), then each damper type at its design over the ladder."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import xarray as xr

from impact.closed_form.tmd import tuned_for
from impact.engine.run import simulate
from impact.engine.spectra import spectral_acceleration
from impact.model.building import Building
from impact.model.kinds import kind_of
from impact.model.params import G_GRAV
from impact.model.records import Record
from impact.model.scene import GroundMotion, Scene
from impact.model.suites import load_suite_record
from impact.outputs.files import as_integers, flag
from impact.outputs.labels import EVENT_CAP_MEANINGS
from impact.stages.buildings import impact_damper, make_building
from impact.stages.ida.plan import AT_LIMIT, MEASURES, SCALED, WHOLE, ladder, motions, scales_linearly

INITIAL_CONDITION = "building and damper at rest; an impact damper's mass centred between its walls"
STROKE_LIMIT_ATTRS = {"long_name": "largest stroke of a damper's mass from its rest place that the building houses: "
                                   "a TMD's end stops, half an impact damper's clearance at most", "units": "m"}


def scaled_motion(record: Record, sa_record_g: float, level_g: float) -> GroundMotion:
    """The record scaled so that its Sa(T1) is level_g."""
    return GroundMotion(record.accel_g * (G_GRAV * level_g / sa_record_g), record.dt, record.name)


def measure(building: Building, dampers: tuple, load: GroundMotion, storey_height: float) -> dict:
    """The measures of one run (SI units), over the record's length: the roof's peaks, the largest drift and the
    strokes, certified; no RMS (not read)."""
    res = simulate(Scene(building, dampers, load), measures=("impacts", "roof", "largest_drift", "strokes"))
    return {"drift_ratio": res.peak_interstorey_drift / storey_height, "peak_roof": res.peak_roof_displacement,
            "peak_accel": res.peak_roof_acceleration,
            "stroke": float(np.max(res.peak_strokes)) if len(res.peak_strokes) else math.nan,
            "impacts": res.impacts, "energy_residual": res.diagnostics["energy_residual"],
            "event_cap_reached": int(bool(res.diagnostics["event_cap_reached"]))}


def over_ladder(run_at, levels: list[float], linear: bool) -> dict:
    """measure -> values over the ladder: a linear case runs once at 1 g and scales, the others run every level."""
    if not linear:
        rows = [run_at(level) for level in levels]
        return {name: np.array([r[name] for r in rows], dtype=float) for name in MEASURES}
    unit = run_at(1.0)
    scale = np.asarray(levels, dtype=float)
    return {name: unit[name] * scale if name in SCALED else np.full(len(levels), float(unit[name]))
            for name in MEASURES}


def within_stops(free_at, stopped_at, levels: list[float], stroke_limit: float) -> dict:
    """A damper linear but for its end stops, over the ladder: its run without stops at 1 g, scaled, stands for each
    level where that stroke stays inside the stops by more than plan.AT_LIMIT (they are never struck there, so the
    run with them is the same motion); the other levels run with the stops."""
    out = over_ladder(free_at, levels, linear=True)
    struck = [i for i, stroke in enumerate(out["stroke"]) if stroke >= stroke_limit * (1.0 - AT_LIMIT)]
    if struck:
        runs = over_ladder(stopped_at, [levels[i] for i in struck], linear=False)
        for name in MEASURES:
            out[name][struck] = runs[name]
    return out


def ladder_of(building: Building, dampers: tuple, run_with, levels: list[float]) -> dict:
    """measure -> values over the ladder of one case, run as seldom as exactness allows: a linear case once, scaled;
    one linear but for a damper's end stops, scaled where they are out of reach; the others at every level.
    run_with(dampers, level) is one run's measures."""
    if scales_linearly(building, dampers):
        return over_ladder(lambda level: run_with(dampers, level), levels, linear=True)
    if len(dampers) == 1 and dampers[0].stroke_limit is not None:
        free = (replace(dampers[0], stroke_limit=None),)
        if scales_linearly(building, free):
            return within_stops(lambda level: run_with(free, level), lambda level: run_with(dampers, level), levels,
                                dampers[0].stroke_limit)
    return over_ladder(lambda level: run_with(dampers, level), levels, linear=False)


def _suite(cfg: dict) -> dict[str, Record]:
    return {key: load_suite_record(key) for key in motions(cfg)}


def _described(ds: xr.Dataset, cfg: dict, building_name: str, building: Building, kind: str) -> xr.Dataset:
    for name, (text, units) in MEASURES.items():
        if name in ds:
            ds[name].attrs = flag(text, *EVENT_CAP_MEANINGS) if units is None else {"long_name": text, "units": units}
    ds = as_integers(ds, WHOLE)
    ds["level"].attrs = {"long_name": "spectral acceleration Sa(T1, 5 %) the ground motion is scaled to, over "
                                      "standard gravity (Sa in g)", "units": "1"}
    ds = ds.assign_coords(sa=("level", ds["level"].values * G_GRAV,
                              {"long_name": "spectral acceleration Sa(T1, 5 %) the ground motion is scaled to",
                               "units": "m s-2"}))
    ds["motion"].attrs = {"long_name": "FEMA P695 ground motion (suite:record:component)"}
    ds.attrs.update(title=f"Incremental dynamic analysis: building {building_name}, {kind}", building=building_name,
                    damper=kind, storeys=building.storeys, period1_s=building.period1, zeta=building.zeta,
                    storey_height_m=cfg["storey_height_m"], total_mass_kg=building.total_mass,
                    initial_condition=INITIAL_CONDITION)
    return ds


def bare_runs(cfg: dict, loads: dict, building_name: str) -> xr.Dataset:
    """The bare building under every ground motion at every level, and each motion's Sa(T1) as recorded."""
    building = make_building(loads, building_name)
    levels, records = ladder(cfg), _suite(cfg)
    sa = {key: spectral_acceleration(rec, building.period1) for key, rec in records.items()}
    columns = [ladder_of(building, (), _runner(building, records[key], sa[key], cfg), levels) for key in records]
    ds = _stack(columns, list(records), levels)
    ds["sa_record"] = ("motion", np.array([sa[k] for k in records]),
                       {"long_name": "Sa(T1, 5 %) of the ground motion as recorded, over standard gravity (Sa in g)",
                        "units": "1"})
    ds = ds.assign_coords(group=("motion", [rec.metadata["group"] for rec in records.values()],
                                 {"long_name": "record group (far-field, near-field pulse, near-field no pulse)"}))
    return _described(ds, cfg, building_name, building, "bare")


def _stack(columns: list[dict], keys: list[str], levels: list[float]) -> xr.Dataset:
    """Per-motion columns of measures over the ladder -> a dataset over (motion, level)."""
    data = {name: (("motion", "level"), np.stack([c[name] for c in columns])) for name in MEASURES}
    return xr.Dataset(data, coords={"motion": keys, "level": levels})


def design_peak(bare: xr.Dataset, design_sa_g: float) -> float:
    """The bare building's peak roof displacement at the design level: the median over the ground motions."""
    return float(bare["peak_roof"].sel(level=design_sa_g).median())


def _runner(building: Building, record: Record, sa_record_g: float, cfg: dict):
    """run_with(dampers, level): the measures of one run of the building with `dampers` under the record scaled to
    the level."""
    return lambda dampers, level: measure(building, dampers, scaled_motion(record, sa_record_g, level),
                                          cfg["storey_height_m"])


def designed_damper(loads: dict, ida: dict, building: Building, kind: str, mass_ratio: float,
                    gap_ratios: dict[float, float], peak: float):
    """The earthquake study's design of one damper: a TMD Den Hartog-tuned to the first mode; an impact damper with
    the clearance its design gap ratio times the bare building's median peak roof displacement at the design level.
    Each within ida's stroke limit (none when null), as a building could house it: an impact damper's clearance is
    twice the limit at most; a TMD's travel ends at stops at the limit, struck with the impact dampers' restitution."""
    limit = ida["stroke_limit_m"]
    if not kind_of(kind).walls:
        tmd = tuned_for(building, mass_ratio)
        return tmd if limit is None else replace(tmd, stroke_limit=limit, e=loads["e"])
    gap = gap_ratios[mass_ratio] * peak
    return impact_damper(kind, building, mass_ratio, gap if limit is None else min(gap, 2.0 * limit), loads["e"])


def damper_runs(cfg: dict, loads: dict, building_name: str, kind: str, bare: xr.Dataset,
                gap_ratios: dict[float, float]) -> xr.Dataset:
    """One damper type on one building, at each mass ratio, under every ground motion over the ladder.

    gap_ratios: mass ratio -> the earthquake study's design gap ratio (impact dampers; empty for the TMD)."""
    building = make_building(loads, building_name)
    levels, records = ladder(cfg), _suite(cfg)
    sa = dict(zip(bare["motion"].values.tolist(), bare["sa_record"].values.tolist()))
    peak = design_peak(bare, cfg["design_sa_g"])
    parts = []
    for mr in loads["mass_ratios"]:
        damper = designed_damper(loads, cfg, building, kind, mr, gap_ratios, peak)
        columns = [ladder_of(building, (damper,), _runner(building, records[key], sa[key], cfg), levels)
                   for key in records]
        part = _stack(columns, list(records), levels)
        if kind_of(kind).walls:
            part["gap"] = ((), damper.gap, {"long_name": "clearance of each impact damper unit: the design gap ratio "
                                                         "times the design peak, at most twice the stroke limit",
                                            "units": "m"})
            part["gap_ratio"] = ((), gap_ratios[mr], {"long_name": "design clearance over the bare building's median "
                                                                   "peak roof displacement at the design level",
                                                      "units": "1"})
        parts.append(part)
    ds = xr.concat(parts, dim="mass_ratio").assign_coords(mass_ratio=list(loads["mass_ratios"]))
    ds["mass_ratio"].attrs = {"long_name": "damper mass over the building's total mass", "units": "1"}
    ds = ds.assign_coords(group=bare["group"])
    if cfg["stroke_limit_m"] is not None:
        ds["stroke_limit"] = ((), cfg["stroke_limit_m"], STROKE_LIMIT_ATTRS)
    return _described(ds, cfg, building_name, building, kind)


def design_gap_ratios(loads_runs: list) -> dict[float, float]:
    """mass ratio -> the earthquake study's design gap ratio, from its run of this building and damper (none: TMD)."""
    if not loads_runs:
        return {}
    best = xr.load_dataset(loads_runs[0])["records_design_gap_ratio"]
    return {float(mr): float(best.sel(mass_ratio=mr)) for mr in best["mass_ratio"].values}
