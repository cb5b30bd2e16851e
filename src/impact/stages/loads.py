"""The earthquake and wind study: the CID, PID and TMD on shear buildings under real and random loads.

Each building is uniform (equal floors and storeys), with the fundamental period and modal damping asked.
Each damper sits on the roof with a mass that is a fraction of the building's total mass:

* the CID and the PID (tuned to the fundamental, r' = 1) with the restitution asked, and a clearance sized from
  the bare building: d = g x (its peak roof displacement under the design-level load).  For a real record the
  design level is that record scaled to the design PGA; for the random loads, the median over the seeds at
  that level.  The gap ratio g is swept on the real records, and the best one (the lowest mean peak roof
  displacement over the records and intensities) is the design the random loads are run with;
* the TMD tuned to the first mode by Den Hartog's rules, with its mass ratio taken over the first mode's
  modal mass (mode shape 1 at the roof).

A ground-motion run lasts the record's length (the peaks come in the strong phase), a wind run its own
duration.  Every measure of a damped run is divided by the bare building's under the same load: peak and RMS roof
displacement, peak absolute roof acceleration, peak inter-storey drift.  Beside them the damper's stroke, its
impact count and the momentum it exchanges per impact.

Scale: a ground motion scaled by s with the gap d fixed is the motion at 1 with the gap d / s, scaled by s (the
dampers are linear between rigid impacts).  So only ratios of the gap to the response matter, and the wind's
absolute strength does not (its gap is sized from its own bare response).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr

from impact.closed_form.tmd import den_hartog
from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.params import G_GRAV, ParameterError
from impact.model.records import kanai_tajimi, load_record, narrow_band_force
from impact.model.scene import DAMPER_KINDS, Damper, ForceRecord, GroundMotion, Scene

FAMILIES = ("records", "kanai_tajimi", "wind")
# the responses judged against the bare building: measure -> the SceneResult attribute
RESPONSES = {"peak_roof": "peak_roof_displacement", "rms_roof": "rms_roof_displacement",
             "peak_accel": "peak_roof_acceleration", "peak_drift": "peak_interstorey_drift"}
IMPACT_RECORDS = 50_000   # impacts whose momentum is kept per run (more are counted, not kept)
SAME = 0.05               # a ratio within 5 % of 1: the damper "does nothing"


def building_id(storeys: int, period_s: float) -> str:
    return f"s{int(storeys)}_T{period_s:g}"


def buildings(cfg: dict) -> dict:
    """id -> (storeys, period) of every building of the stage."""
    return {building_id(n, t): (n, t) for n in cfg["storeys"] for t in cfg["periods_s"]}


def make_building(cfg: dict, building: str) -> Building:
    storeys, period = buildings(cfg)[building]
    return Building.uniform(storeys, period, cfg["zeta"])


def first_modal_mass(building: Building) -> float:
    """The first mode's modal mass with the mode shape scaled to 1 at the roof."""
    _, phi = building.modes()
    shape = phi[:, 0] / phi[-1, 0]
    return float(shape @ (building.masses * shape))


def tmd_damper(building: Building, mass_ratio: float) -> Damper:
    """A TMD of mass_ratio x the building's mass on the roof, Den Hartog-tuned to the first mode."""
    mass = mass_ratio * building.total_mass
    tuning = den_hartog(mass / first_modal_mass(building))
    return Damper("tmd", mass=mass, tuning=tuning["f"], damping=tuning["beta_t"])


def impact_damper(kind: str, building: Building, mass_ratio: float, gap: float, e: float) -> Damper:
    return Damper(kind, mass=mass_ratio * building.total_mass, gap=gap, e=e, tuning=1.0 if kind == "pid" else 0.0)


# ----------------------------------------------------------------------------
# the loads
# ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Load:
    """One load of the stage: its family, its labels in the datasets, and the scene load."""

    family: str
    labels: dict
    load: object
    duration: float | None = None


def real_loads(cfg: dict) -> list[Load]:
    recs = {name: load_record(name) for name in cfg["records"]["names"]}
    return [Load("records", {"record": name, "intensity": pga}, GroundMotion.from_record(rec, pga_g=pga))
            for name, rec in recs.items() for pga in cfg["records"]["pga_g"]]


def kt_record(cfg: dict, soil: str, seed: int):
    kt = cfg["kanai_tajimi"]
    return kanai_tajimi(seed, kt["duration_s"], kt["dt_s"], soil=soil, pga_g=1.0,
                        envelope_params=(kt["rise_s"], kt["plateau_end_s"], kt["decay_per_s"]))


def random_loads(cfg: dict) -> list[Load]:
    kt, out = cfg["kanai_tajimi"], []
    for soil in kt["soils"]:
        for seed in range(kt["seeds"]):
            rec = kt_record(cfg, soil, seed)
            out += [Load("kanai_tajimi", {"soil": soil, "seed": seed, "intensity": pga},
                         GroundMotion.from_record(rec, pga_g=pga)) for pga in cfg["records"]["pga_g"]]
    return out


def wind_loads(cfg: dict, building: Building) -> list[Load]:
    """The narrow-band random force on every floor, centred on the first mode (rms: a share of each floor's weight)."""
    w = cfg["wind"]
    dt = w["dt_periods"] * building.period1
    duration = w["duration_periods"] * building.period1
    out = []
    for seed in range(w["seeds"]):
        values = narrow_band_force(seed, duration, dt, building.omega1, bandwidth=w["bandwidth"],
                                   rms=w["rms_weight_share"] * G_GRAV)
        out.append(Load("wind", {"seed": seed}, ForceRecord(values, dt, building.masses.copy(), name=f"wind-{seed}"),
                        duration))
    return out


# ----------------------------------------------------------------------------
# one run and its measures
# ----------------------------------------------------------------------------

def run(building: Building, dampers: tuple, load: Load) -> dict:
    """The measures of one scene run (SI units)."""
    res = simulate_scene(Scene(building, dampers, load.load, duration=load.duration),
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


# ----------------------------------------------------------------------------
# datasets
# ----------------------------------------------------------------------------

MEASURES = {
    "peak_roof": ("peak roof displacement", "m"),
    "rms_roof": ("RMS roof displacement", "m"),
    "peak_accel": ("peak absolute roof acceleration", "m s-2"),
    "peak_drift": ("peak inter-storey drift", "m"),
    "stroke": ("largest stroke of the damper mass relative to the roof", "m"),
    "impacts": ("number of impacts", "1"),
    "impulse_mean": ("mean momentum exchanged per impact", "N s"),
    "impulse_max": ("largest momentum exchanged in one impact", "N s"),
    "energy_residual": ("energy balance residual of the run, relative", "1"),
    "event_cap_reached": ("the run stopped at the event cap (0 or 1)", "1"),
}
LABEL_DIMS = {"records": ("record", "intensity"), "kanai_tajimi": ("soil", "seed", "intensity"),
              "wind": ("wind_seed",)}
COORD_ATTRS = {
    "record": {"long_name": "ground-motion record"},
    "intensity": {"long_name": "peak ground acceleration the load is scaled to", "units": "g"},
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
    import pandas as pd

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
        text, units = MEASURES[name.removeprefix(family + "_")]
        ds[name].attrs = {"long_name": f"{text}, {family.replace('_', '-')} loads", "units": units}
    for name in ds.coords:
        ds[name].attrs = COORD_ATTRS[name]
    return ds


# ----------------------------------------------------------------------------
# the stage's jobs: the bare building, one damper type, the collection
# ----------------------------------------------------------------------------

def stage_loads(cfg: dict, building_name: str, building: Building) -> list[Load]:
    loads = real_loads(cfg) + random_loads(cfg)
    if building_name in cfg["wind"]["buildings"]:
        loads += wind_loads(cfg, building)
    return loads


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
        if kind == "tmd":
            rows += [row(ld, run(building, (tmd_damper(building, mr),), ld), mass_ratio=mr) for ld in loads]
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
        elif kind != "tmd":
            out[f"{family}_design_gap_ratio"] = out["records_design_gap_ratio"].assign_attrs(
                long_name=f"gap ratio of the design, {family} loads (the records' best)")
        for name in names:
            out[name] = part[name].dropna("gap_ratio", how="all") if "gap_ratio" in part[name].dims else part[name]
            key = name.removeprefix(family + "_")
            if key in RESPONSES:
                out[f"{name}_ratio"] = (part[name] / bare[name]).assign_attrs(
                    long_name=f"{MEASURES[key][0]} over the bare building's, {family} loads", units="1")
    return xr.Dataset(out)


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
                       xr.concat(bare_parts, dim="building")]).assign_coords(building=names)
        for name in ds.data_vars:
            if name.startswith("bare_"):
                ds[name].attrs = dict(bare[names[0]][f"{family}_{name.removeprefix('bare_')}"].attrs)
                ds[name].attrs["long_name"] = "bare building: " + ds[name].attrs["long_name"]
        ds["building"].attrs = COORD_ATTRS["building"]
        ds["damper"].attrs = COORD_ATTRS["damper"]
        out[family] = ds
    return out


def _family(ds: xr.Dataset, family: str) -> xr.Dataset:
    """The family's variables with the family prefix dropped."""
    names = [n for n in ds.data_vars if n.startswith(family + "_")]
    return ds[names].rename({n: n.removeprefix(family + "_") for n in names})


# ----------------------------------------------------------------------------
# what the stage says: the best damper per building and intensity, and where each helps or harms
# ----------------------------------------------------------------------------

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
    import pandas as pd

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
    import pandas as pd

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
                    where = ", ".join(f"{d} {worst[d].values}" for d in r.dims)
                    values = flat.values
                    rows.append({"damper": str(damper), "mass_ratio": float(mr), "load": label, "measure": measure,
                                 "cases": int(values.size), "helps": int(np.sum(values < 1 - SAME)),
                                 "does_nothing": int(np.sum(np.abs(values - 1) <= SAME)),
                                 "makes_worse": int(np.sum(values > 1 + SAME)),
                                 "median_ratio": float(np.median(values)), "worst_ratio": float(values.max()),
                                 "worst_case": where})
    return pd.DataFrame(rows)


def time_history(cfg: dict, building_name: str, record: str, kind: str, mass_ratio: float, gap_ratio: float,
                 bare: xr.Dataset, samples_per_period: int = 50) -> xr.Dataset:
    """One case in time: the roof with and without the damper, the damper's stroke, and its impacts."""
    building = make_building(cfg, building_name)
    pga = cfg["records"]["design_pga_g"]
    load = Load("records", {"record": record, "intensity": pga},
                GroundMotion.from_record(load_record(record), pga_g=pga))
    damper = _impact(cfg, kind, building, mass_ratio, gap_ratio, bare, load)
    times = np.arange(0.0, load.load.duration, building.period1 / samples_per_period)
    roof = building.storeys - 1
    plain = simulate_scene(Scene(building, (), load.load), times=times)
    damped = simulate_scene(Scene(building, (damper,), load.load), times=times, record=IMPACT_RECORDS)
    q = damped.samples["q"]
    data = {
        "roof_bare": ("t", plain.samples["q"][:, roof], {"long_name": "roof displacement, bare building",
                                                            "units": "m"}),
        "roof_damped": ("t", q[:, roof], {"long_name": f"roof displacement with the {kind.upper()}", "units": "m"}),
        "stroke": ("t", q[:, building.storeys] - q[:, roof],
                   {"long_name": "damper mass relative to the roof", "units": "m"}),
        "impact_time": ("impact", damped.records["t"], {"long_name": "time of each impact", "units": "s"}),
        "impact_impulse": ("impact", np.abs(damped.records["impulse"]),
                           {"long_name": "momentum exchanged in the impact", "units": "N s"}),
        "half_gap": ((), 0.5 * damper.gap, {"long_name": "half the clearance: where the walls are", "units": "m"}),
    }
    # "t", not "time": CF reserves a coordinate named time for dates ("seconds since ...")
    ds = xr.Dataset(data, coords={"t": ("t", times, {"long_name": "time since the record's start", "units": "s"})})
    ds.attrs.update(title=f"Loads study: one case in time ({building_name}, {record} at {pga:g} g, "
                          f"{kind.upper()} of {mass_ratio:g} of the mass, g = {gap_ratio:g})",
                    building=building_name, record=record, pga_g=pga, damper=kind, mass_ratio=mass_ratio,
                    gap_ratio=gap_ratio, initial_condition="building and damper at rest; damper mass centred")
    return ds


def check_config(cfg: dict) -> None:
    """Checks of the loads section a JSON schema cannot express; the message names the key."""
    names = buildings(cfg)
    if cfg["records"]["design_pga_g"] not in cfg["records"]["pga_g"]:
        raise ParameterError(f"loads.records.design_pga_g = {cfg['records']['design_pga_g']} must be one of "
                             f"loads.records.pga_g = {cfg['records']['pga_g']}")
    for b in cfg["wind"]["buildings"]:
        if b not in names:
            raise ParameterError(f"loads.wind.buildings: {b!r} is not a building of the stage ({', '.join(names)})")
    th = cfg["time_history"]
    if th["building"] not in names:
        raise ParameterError(f"loads.time_history.building = {th['building']!r} is not a building of the stage "
                             f"({', '.join(names)})")
    if th["mass_ratio"] not in cfg["mass_ratios"]:
        raise ParameterError(f"loads.time_history.mass_ratio = {th['mass_ratio']} must be one of "
                             f"loads.mass_ratios = {cfg['mass_ratios']}")
    if th["record"] not in cfg["records"]["names"]:
        raise ParameterError(f"loads.time_history.record = {th['record']!r} must be one of loads.records.names")


def families(cfg: dict) -> list[str]:
    """The load families the stage runs (the wind only when it loads a building)."""
    return [f for f in FAMILIES if f != "wind" or cfg["wind"]["buildings"]]
