"""The earthquake and wind study's runs on the exact engine: bare buildings, dampers over their gap ratios,
the time histories."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from impact.closed_form.tmd import tuned_for
from impact.engine.run import simulate
from impact.model.building import Building
from impact.model.kinds import kind_of
from impact.model.scene import Damper, GroundMotion, Scene
from impact.model.suites import record_by_key
from impact.outputs.datasets import time_history_dataset
from impact.outputs.labels import label
from impact.stages.buildings import impact_damper, make_building
from impact.stages.loads.plan import IMPACT_RECORDS, RESPONSES, Load, stage_loads
from impact.stages.loads.tables import (
    LABEL_DIMS,
    MEASURES,
    _described,
    row,
    rows_dataset,
)


def run(building: Building, dampers: tuple, load: Load) -> dict:
    """The measures of one scene run (SI units)."""
    res = simulate(Scene(building, dampers, load.load, duration=load.duration),
                   measures=("amplitude", "impacts", "peaks", "records"),
                   record=IMPACT_RECORDS if dampers and dampers[0].has_walls else 0)
    out = {key: getattr(res, attr) for key, attr in RESPONSES.items()}
    out["stroke"] = float(np.max(res.peak_strokes)) if len(res.peak_strokes) else math.nan
    out["impacts"] = res.impacts
    impulses = np.abs(res.records["impulse"]) if res.records is not None else np.zeros(0)
    out["impulse_mean"] = float(np.mean(impulses)) if len(impulses) else math.nan
    out["impulse_max"] = float(np.max(impulses)) if len(impulses) else math.nan
    out["energy_residual"] = res.diagnostics["energy_residual"]
    out["event_cap_reached"] = bool(res.diagnostics["event_cap_reached"])
    return out


def bare_runs(cfg: dict, building_name: str) -> xr.Dataset:
    """The bare building under every load of the stage."""
    building = make_building(cfg, building_name)
    rows = [row(ld, run(building, (), ld)) for ld in stage_loads(cfg, building_name, building)]
    return _described(rows_dataset(rows, ()), building_name, building, "none")


def design_peak(bare: xr.Dataset, load: Load, cfg: dict) -> float:
    """The bare building's peak roof displacement at the design level of this load: a record's own at the
    design PGA; the median over the seeds for the random loads."""
    pga = cfg["records"]["design_pga_g"]
    if load.family == "records":
        return float(bare["records_peak_roof"].sel(record=load.labels["record"], intensity=pga))
    if load.family == "kanai_tajimi":
        return float(bare["kanai_tajimi_peak_roof"].sel(soil=load.labels["soil"], intensity=pga).median())
    return float(bare["wind_peak_roof"].median())


def _best_gap(ds: xr.Dataset, bare: xr.Dataset, family: str) -> xr.DataArray:
    """Per mass ratio, the swept gap ratio with the lowest peak roof displacement over the bare building's,
    averaged over the family's loads."""
    ratio = ds[f"{family}_peak_roof"] / bare[f"{family}_peak_roof"]
    return ratio.mean([d for d in ratio.dims if d not in ("mass_ratio", "gap_ratio")]).idxmin("gap_ratio")


def damper_runs(cfg: dict, building_name: str, kind: str, bare: xr.Dataset) -> xr.Dataset:
    """One damper type on one building under every load, at each mass ratio; for the CID and PID the gap
    ratio is swept on the records (and the wind) and the random loads run at the records' best gap."""
    building = make_building(cfg, building_name)
    loads = stage_loads(cfg, building_name, building)
    rows = []
    for mr in cfg["mass_ratios"]:
        if not kind_of(kind).walls:
            rows += [row(ld, run(building, (tuned_for(building, mr),), ld), mass_ratio=mr) for ld in loads]
            continue
        swept = [ld for ld in loads if ld.family != "kanai_tajimi"]
        sweep_rows = [row(ld, run(building, (_impact(cfg, kind, building, mr, g, bare, ld),), ld), mass_ratio=mr,
                          gap_ratio=g) for g in cfg["gap_ratios"] for ld in swept]
        best = float(_best_gap(rows_dataset(sweep_rows, ("mass_ratio", "gap_ratio")), bare, "records").item())
        rows += sweep_rows
        rows += [row(ld, run(building, (_impact(cfg, kind, building, mr, best, bare, ld),), ld), mass_ratio=mr)
                 for ld in loads if ld.family == "kanai_tajimi"]
    ds = rows_dataset(rows, ("mass_ratio", "gap_ratio"))
    return _described(_at_design(ds, bare, kind), building_name, building, kind)


def _impact(cfg, kind, building, mass_ratio, gap_ratio, bare, load) -> Damper:
    return impact_damper(kind, building, mass_ratio, gap_ratio * design_peak(bare, load, cfg), cfg["e"])


def _at_design(ds: xr.Dataset, bare: xr.Dataset, kind: str) -> xr.Dataset:
    """Each family's measures at the damper's design (the best gap ratio of the records, or of the wind for the
    wind), their ratios to the bare building's, and the swept peak roof ratio."""
    out = {}
    for family in LABEL_DIMS:
        names = [n for n in ds.data_vars if n.startswith(family + "_")]
        if not names:
            continue
        part = ds[names]
        if "gap_ratio" in part[f"{family}_peak_roof"].dims:
            swept = part[f"{family}_peak_roof"] / bare[f"{family}_peak_roof"]
            out[f"{family}_peak_roof_ratio_vs_gap"] = swept.assign_attrs(
                long_name=f"peak roof displacement over the bare building's, {family} loads, per gap ratio",
                units="1")
            best = _best_gap(part, bare, family)
            part = part.sel(gap_ratio=best).drop_vars("gap_ratio")
            out[f"{family}_design_gap_ratio"] = best.assign_attrs(long_name=f"gap ratio of the design, {family} loads",
                                                           units="1")
        elif kind_of(kind).walls:
            out[f"{family}_design_gap_ratio"] = out["records_design_gap_ratio"].assign_attrs(
                long_name=f"gap ratio of the design, {family} loads (the records' best)")
        for name in names:
            out[name] = part[name].dropna("gap_ratio", how="all") if "gap_ratio" in part[name].dims else part[name]
            key = name.removeprefix(family + "_")
            if key in RESPONSES:
                out[f"{name}_ratio"] = (part[name] / bare[name]).assign_attrs(
                    long_name=f"{MEASURES[key][0]} over the bare building's, {family} loads", units="1")
    return xr.Dataset(out)


def time_history(cfg: dict, building_name: str, record: str, kind: str, mass_ratio: float, gap_ratio: float,
                 bare: xr.Dataset, samples_per_period: int = 50) -> xr.Dataset:
    """One case in time: the roof with and without the damper, the damper's stroke, and its impacts."""
    building = make_building(cfg, building_name)
    pga = cfg["records"]["design_pga_g"]
    load = Load("records", {"record": record, "intensity": pga},
                GroundMotion.from_record(record_by_key(record), pga_g=pga))
    damper = _impact(cfg, kind, building, mass_ratio, gap_ratio, bare, load)
    times = np.arange(0.0, load.load.duration, building.period1 / samples_per_period)
    roof = building.storeys - 1
    plain = simulate(Scene(building, (), load.load), measures=("peaks", "samples"), times=times)
    damped = simulate(Scene(building, (damper,), load.load), measures=("peaks", "records", "samples"), times=times,
                      record=IMPACT_RECORDS)
    q = damped.samples["q"]
    title = (f"Loads study: one case in time ({label(building_name)}, {record} at {pga:g} g, "
             f"{kind.upper()} of {mass_ratio:g} of the mass, clearance {gap_ratio:g} x the bare peak roof displacement)")
    ds = time_history_dataset(times, q[:, roof], q[:, building.storeys] - q[:, roof], 0.5 * damper.gap,
                              damped.records["t"], damped.records["impulse"], length_unit="m", impulse_unit="N s",
                              title=title, kind=kind, roof_bare=plain.samples["q"][:, roof],
                              building=building_name, record=record, pga_g=pga, mass_ratio=mass_ratio,
                              gap_ratio=gap_ratio, initial_condition="building and damper at rest; damper mass centred")
    return ds
