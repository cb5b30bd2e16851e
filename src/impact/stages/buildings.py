"""The study's buildings and the impact dampers designed for them, shared by the stages on real loads (loads,
ida, collapse): one rule, read from the configuration's ``storeys``, ``periods_s`` and ``zeta``.  The TMD's
design is the closed form's (:func:`impact.closed_form.tmd.tuned_for`).  Nothing here runs the engine."""

from __future__ import annotations

from impact.model.building import Building
from impact.model.kinds import kind_of
from impact.model.scene import Damper


def building_id(storeys: int, period_s: float) -> str:
    return f"s{int(storeys)}_T{period_s:g}"


def buildings(cfg: dict) -> dict:
    """id -> (storeys, period) of every building of a stage."""
    return {building_id(n, t): (n, t) for n in cfg["storeys"] for t in cfg["periods_s"]}


def make_building(cfg: dict, building: str) -> Building:
    storeys, period = buildings(cfg)[building]
    return Building.uniform(storeys, period, cfg["zeta"])


def impact_damper(kind: str, building: Building, mass_ratio: float, gap: float, e: float) -> Damper:
    """An impact damper of mass_ratio x the building's mass on its roof (a pendulum tuned to its first mode)."""
    return Damper(kind, mass=mass_ratio * building.total_mass, gap=gap, e=e,
                  tuning=1.0 if kind_of(kind).spring else 0.0)
