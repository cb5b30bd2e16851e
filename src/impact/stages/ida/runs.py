"""The incremental dynamic analysis's runs on the exact engine: per building, the bare building (with every ground
motion's Sa(T1)), then each damper type at its design over the ladder."""

from __future__ import annotations

import math

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
from impact.stages.ida.plan import MEASURES, SCALED, WHOLE, ladder, motions, scales_linearly

INITIAL_CONDITION = "building and damper at rest; an impact damper's mass centred between its walls"


def scaled_motion(record: Record, sa_record_g: float, level_g: float) -> GroundMotion:
    """The record scaled so that its Sa(T1) is level_g."""
    return GroundMotion(record.accel_g * (G_GRAV * level_g / sa_record_g), record.dt, record.name)


def measure(building: Building, dampers: tuple, load: GroundMotion, storey_height: float) -> dict:
    """The measures of one run (SI units), over the record's length."""
    res = simulate(Scene(building, dampers, load), measures=("impacts", "peaks"))
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
    columns = [over_ladder(lambda level, key=key: measure(building, (), scaled_motion(records[key], sa[key], level),
                                                           cfg["storey_height_m"]), levels,
                               linear=scales_linearly(building, "bare"))
               for key in records]
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


def designed_damper(loads: dict, building: Building, kind: str, mass_ratio: float, gap_ratios: dict[float, float],
                    peak: float):
    """The earthquake study's design of one damper: a TMD Den Hartog-tuned to the first mode; an impact damper with
    the clearance its design gap ratio times the bare building's median peak roof displacement at the design level."""
    if not kind_of(kind).walls:
        return tuned_for(building, mass_ratio)
    return impact_damper(kind, building, mass_ratio, gap_ratios[mass_ratio] * peak, loads["e"])


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
        damper = designed_damper(loads, building, kind, mr, gap_ratios, peak)
        columns = [over_ladder(lambda level, key=key: measure(building, (damper,),
                                                               scaled_motion(records[key], sa[key], level),
                                                               cfg["storey_height_m"]), levels,
                               linear=scales_linearly(building, kind))
                   for key in records]
        part = _stack(columns, list(records), levels)
        if kind_of(kind).walls:
            part["gap"] = ((), damper.gap, {"long_name": "clearance of each impact damper unit", "units": "m"})
            part["gap_ratio"] = ((), gap_ratios[mr], {"long_name": "clearance over the bare building's median peak "
                                                                   "roof displacement at the design level",
                                                      "units": "1"})
        parts.append(part)
    ds = xr.concat(parts, dim="mass_ratio").assign_coords(mass_ratio=list(loads["mass_ratios"]))
    ds["mass_ratio"].attrs = {"long_name": "damper mass over the building's total mass", "units": "1"}
    ds = ds.assign_coords(group=bare["group"])
    return _described(ds, cfg, building_name, building, kind)


def design_gap_ratios(loads_runs: list) -> dict[float, float]:
    """mass ratio -> the earthquake study's design gap ratio, from its run of this building and damper (none: TMD)."""
    if not loads_runs:
        return {}
    best = xr.load_dataset(loads_runs[0])["records_design_gap_ratio"]
    return {float(mr): float(best.sel(mass_ratio=mr)) for mr in best["mass_ratio"].values}
