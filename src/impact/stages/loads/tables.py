"""The earthquake and wind study's datasets and tables: rows into datasets, the families joined over
the buildings, the best damper and each damper's verdicts (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from impact.model.building import Building
from impact.model.params import G_GRAV
from impact.model.scene import DAMPER_KINDS
from impact.outputs.files import as_integers, flag
from impact.outputs.labels import EVENT_CAP_MEANINGS, RUN_MEASURES, load_case
from impact.stages.loads.plan import (
    RESPONSES,
    SAME,
    Load,
)

MEASURES = {
    "peak_roof": ("peak roof displacement", "m"),
    "rms_roof": ("RMS roof displacement", "m"),
    "peak_accel": RUN_MEASURES["peak_accel"],
    "peak_drift": ("peak inter-storey drift", "m"),
    "stroke": RUN_MEASURES["stroke"],
    "impacts": RUN_MEASURES["impacts"],
    "impulse_mean": ("mean momentum exchanged per impact", "N s"),
    "impulse_max": ("largest momentum exchanged in one impact", "N s"),
    "energy_residual": RUN_MEASURES["energy_residual"],
    "event_cap_reached": RUN_MEASURES["event_cap_reached"],
}
#: the measures that are counts or flags (stored as integers); a flag's units are its meanings
WHOLE = ("impacts", "event_cap_reached")


LABEL_DIMS = {"records": ("record", "intensity"), "kanai_tajimi": ("soil", "seed", "intensity"),
              "wind": ("wind_seed",)}


COORD_ATTRS = {
    "record": {"long_name": "ground-motion record"},
    # the index stays in g, as the configuration gives it; pga beside it is the same in SI units
    "intensity": {"long_name": "peak ground acceleration the load is scaled to, over standard gravity (PGA in g)",
                  "units": "1"},
    "pga": {"long_name": "peak ground acceleration the load is scaled to", "units": "m s-2"},
    "soil": {"long_name": "Kanai-Tajimi soil"},
    "seed": {"long_name": "seed of the Kanai-Tajimi realisation", "units": "1"},
    "wind_seed": {"long_name": "seed of the narrow-band wind force", "units": "1"},
    "mass_ratio": {"long_name": "damper mass over the building's total mass", "units": "1"},
    "gap_ratio": {"long_name": "clearance over the bare building's peak roof displacement at the design level",
                  "units": "1"},
    "building": {"long_name": "building: storeys and fundamental period"},
    "damper": {"long_name": "damper type"},
}


def row(load: Load, measures: dict, **lead) -> dict:
    """One run as a row: its lead labels (mass ratio, gap ratio), its load's labels, its measures."""
    labels = dict(load.labels)
    if load.family == "wind":
        labels["wind_seed"] = labels.pop("seed")
    return {"family": load.family, **lead, **labels, **measures}


def rows_dataset(rows: list[dict], lead: tuple) -> xr.Dataset:
    """Every family's runs as variables '<family>_<measure>' over (lead..., the family's labels)."""

    frame = pd.DataFrame(rows)
    parts = []
    for family, dims in LABEL_DIMS.items():
        sub = frame[frame["family"] == family]
        if sub.empty:
            continue
        index = [d for d in (*lead, *dims) if d in sub and sub[d].notna().all()]
        part = sub.set_index(index)[list(MEASURES)].astype(float).to_xarray()
        part = part.assign_coords({d: part[d].astype(int) for d in ("seed", "wind_seed") if d in part.coords})
        parts.append(part.rename({m: f"{family}_{m}" for m in MEASURES}))
    ds = xr.merge(parts, join="outer")
    for name in ds.data_vars:
        family = next(f for f in LABEL_DIMS if name.startswith(f + "_"))
        measure = name.removeprefix(family + "_")
        text, units = MEASURES[measure]
        long_name = f"{text}, {family.replace('_', '-')} loads"
        ds[name].attrs = (flag(long_name, *EVENT_CAP_MEANINGS) if units is None
                          else {"long_name": long_name, "units": units})
    if "intensity" in ds.coords:
        ds = ds.assign_coords(pga=("intensity", ds["intensity"].values * G_GRAV))
    for name in ds.coords:
        ds[name].attrs = COORD_ATTRS[name]
    return as_integers(ds, [f"{family}_{m}" for family in LABEL_DIMS for m in WHOLE])


def _described(ds: xr.Dataset, building_name: str, building: Building, damper: str) -> xr.Dataset:
    ds.attrs.update(title=f"Loads study: building {building_name}, damper {damper}", building=building_name,
                    damper=damper, storeys=building.storeys, period1_s=building.period1, zeta=building.zeta,
                    total_mass_kg=building.total_mass,
                    initial_condition="building and damper at rest; an impact damper's mass centred between its walls")
    return ds


def collect(bare: dict, dampers: dict) -> dict:
    """Per family, every building and damper in one dataset (dims building, damper, ...): the damped measures,
    their ratios to the bare building's, and the bare measures.

    bare: building -> its bare dataset; dampers: (building, kind) -> its damper dataset."""
    out = {}
    for family in LABEL_DIMS:
        per_building, bare_parts, names = [], [], []
        for name, b in bare.items():
            kinds = [k for k in DAMPER_KINDS if (name, k) in dampers and f"{family}_peak_roof" in dampers[name, k]]
            if not kinds:
                continue
            parts = [_family(dampers[name, k], family) for k in kinds]
            per_building.append(xr.concat(parts, dim="damper", join="outer", coords="minimal", data_vars="all")
                                .assign_coords(damper=kinds))
            kept = _family(b, family)[[*RESPONSES, "energy_residual"]]
            bare_parts.append(kept.rename({v: f"bare_{v}" for v in kept.data_vars}))
            names.append(name)
        if not per_building:
            continue
        ds = xr.merge([xr.concat(per_building, dim="building", join="outer", coords="minimal", data_vars="all"),
                       xr.concat(bare_parts, dim="building")], compat="no_conflicts").assign_coords(building=names)
        for name in ds.data_vars:
            if name.startswith("bare_"):
                ds[name].attrs = dict(bare[names[0]][f"{family}_{name.removeprefix('bare_')}"].attrs)
                ds[name].attrs["long_name"] = "bare building: " + ds[name].attrs["long_name"]
        ds["building"].attrs = COORD_ATTRS["building"]
        ds["damper"].attrs = COORD_ATTRS["damper"]
        ds.attrs = _collected_attrs(family, bare, names, ds)
        out[family] = ds
    return out


#: what each family's collected dataset holds, for its title
FAMILY_TITLES = {"records": "the real earthquake records scaled to each PGA",
                 "kanai_tajimi": "seeded Kanai-Tajimi ground motions per soil, scaled to each PGA",
                 "wind": "seeded narrow-band wind forces on every floor"}


def _collected_attrs(family: str, bare: dict, names: list, ds: xr.Dataset) -> dict:
    """Global attributes of a family's dataset over every building and damper: what it holds, not the first
    piece's values, and the configuration its pieces were run with."""
    first = bare[names[0]].attrs
    configs = {bare[name].attrs.get("config") for name in names}
    if len(configs) > 1:
        raise ValueError(f"loads, {family}: the buildings' runs were made with different configurations")
    return {"title": f"Loads study: {len(names)} buildings x {ds.sizes['damper']} dampers under "
                     f"{FAMILY_TITLES[family]}",
            "buildings": ", ".join(names), "dampers": ", ".join(map(str, ds["damper"].values)),
            "zeta": first["zeta"], "initial_condition": first["initial_condition"],
            **({"config": configs.pop()} if None not in configs else {})}


def _family(ds: xr.Dataset, family: str) -> xr.Dataset:
    """The family's variables with the family prefix dropped."""
    names = [n for n in ds.data_vars if n.startswith(family + "_")]
    return ds[names].rename({n: n.removeprefix(family + "_") for n in names})


def _groups(out: dict):
    """(load label, dataset, the dims averaged over, the intensity dim or None) of each load group."""
    if "records" in out:
        yield "records", out["records"], ("record",), "intensity"
    if "kanai_tajimi" in out:
        for soil in out["kanai_tajimi"]["soil"].values:
            yield f"kanai-tajimi {soil}", out["kanai_tajimi"].sel(soil=soil), ("seed",), "intensity"
    if "wind" in out:
        yield "wind", out["wind"], ("wind_seed",), None


def best_damper_table(out: dict, measure: str = "peak_roof"):
    """One row per building, load group, intensity and mass ratio: each damper's mean ratio to the bare
    building (over the records, or the seeds), and the best damper."""

    rows = []
    for label, ds, over, intensity in _groups(out):
        mean = ds[f"{measure}_ratio"].mean(over)
        for building in ds["building"].values:
            for level in (ds[intensity].values if intensity else [math.nan]):
                for mr in ds["mass_ratio"].values:
                    at = mean.sel(building=building, mass_ratio=mr)
                    at = at.sel({intensity: level}) if intensity else at
                    ratios = {str(k): float(v) for k, v in zip(at["damper"].values, at.values)}
                    best = min(ratios, key=lambda k: ratios[k] if math.isfinite(ratios[k]) else math.inf)
                    rows.append({"building": str(building), "load": label, "intensity_g": level,
                                 "mass_ratio": float(mr), **{f"{k}_{measure}_ratio": v for k, v in ratios.items()},
                                 "best": best, "best_ratio": ratios[best], "best_verdict": verdict(ratios[best])})
    return pd.DataFrame(rows)


def verdict(ratio: float) -> str:
    if not math.isfinite(ratio):
        return "not measured"
    if ratio < 1.0 - SAME:
        return "helps"
    return "does nothing" if ratio <= 1.0 + SAME else "makes it worse"


def verdict_table(out: dict, measures=("peak_roof", "rms_roof", "peak_accel", "peak_drift")):
    """Per damper, mass ratio, load group and measure: how many single runs it helps (ratio < 0.95), leaves
    alone (within 5 %) or makes worse (> 1.05), the median ratio, and the worst case."""

    rows = []
    for label, ds, _, _ in _groups(out):
        for measure in measures:
            ratio = ds[f"{measure}_ratio"]
            for damper in ratio["damper"].values:
                for mr in ratio["mass_ratio"].values:
                    r = ratio.sel(damper=damper, mass_ratio=mr)
                    flat = r.stack(case=r.dims).dropna("case")
                    if flat.size == 0:
                        continue
                    worst = flat.isel(case=int(flat.argmax("case")))
                    where = load_case({d: worst[d].values for d in r.dims})
                    values = flat.values
                    rows.append({"damper": str(damper), "mass_ratio": float(mr), "load": label, "measure": measure,
                                 "cases": int(values.size), "helps": int(np.sum(values < 1 - SAME)),
                                 "does_nothing": int(np.sum(np.abs(values - 1) <= SAME)),
                                 "makes_worse": int(np.sum(values > 1 + SAME)),
                                 "median_ratio": float(np.median(values)), "worst_ratio": float(values.max()),
                                 "worst_case": where})
    return pd.DataFrame(rows)
