"""The earthquake and wind study's plan: its loads and their checks, from the configuration (its buildings and
dampers are the shared ones of stages/buildings.py).
Nothing here runs the engine, so the workflow's start-up reads it without loading numba."""

from __future__ import annotations

from dataclasses import dataclass

from impact.model.building import Building
from impact.model.params import G_GRAV, ParameterError
from impact.model.records import kanai_tajimi, narrow_band_force
from impact.model.scene import ForceRecord, GroundMotion
from impact.model.suites import record_by_key
from impact.stages.buildings import buildings, check_buildings

FAMILIES = ("records", "kanai_tajimi", "wind")


# the responses judged against the bare building: measure -> the SceneResult attribute
RESPONSES = {"peak_roof": "peak_roof_displacement", "rms_roof": "rms_roof_displacement",
             "peak_accel": "peak_roof_acceleration", "peak_drift": "peak_interstorey_drift"}


IMPACT_RECORDS = 50_000   # impacts whose momentum is kept per run (more are counted, not kept)


SAME = 0.05               # a ratio within 5 % of 1: the damper "does nothing"


@dataclass(frozen=True)
class Load:
    """One load of the stage: its family, its labels in the datasets, and the scene load."""

    family: str
    labels: dict
    load: object
    duration: float | None = None


def real_loads(cfg: dict) -> list[Load]:
    recs = {name: record_by_key(name) for name in cfg["records"]["names"]}
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


def stage_loads(cfg: dict, building_name: str, building: Building) -> list[Load]:
    loads = real_loads(cfg) + random_loads(cfg)
    if building_name in cfg["wind"]["buildings"]:
        loads += wind_loads(cfg, building)
    return loads


def check_config(cfg: dict) -> None:
    """Checks of the loads section a JSON schema cannot express; the message names the key."""
    check_buildings(cfg)
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
