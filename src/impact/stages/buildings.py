"""The study's buildings and the impact dampers designed for them, shared by the stages on real loads (loads,
ida, collapse): the uniform ones of the configuration's ``storeys`` x ``periods_s``, and the ones given floor by
floor under ``buildings`` (their own masses and storey stiffnesses), all with the section's ``zeta``.  The TMD's
design is the closed form's (:func:`impact.closed_form.tmd.tuned_for`).  Nothing here runs the engine."""

from __future__ import annotations

import re

from impact.model.building import Building
from impact.model.kinds import kind_of
from impact.model.params import ParameterError
from impact.model.scene import Damper

#: the loads section's keys that make the buildings and damper designs the ida and collapse stages share
SHARED_KEYS = ("storeys", "periods_s", "buildings", "zeta", "mass_ratios", "e")
#: floor masses and storey stiffnesses of a building given floor by floor, as the configuration names them
FLOOR_BY_FLOOR = ("masses_kg", "storey_stiffness_n_per_m")


def shared_keys(loads: dict) -> dict:
    """The slice of the loads section a stage on its buildings and dampers depends on (a key left out of the
    configuration stays out, so that adding one changes no other stage's parameters)."""
    return {key: loads[key] for key in SHARED_KEYS if key in loads}


def building_id(storeys: int, period_s: float) -> str:
    return f"s{int(storeys)}_T{period_s:g}"


def buildings(cfg: dict) -> dict:
    """id -> how a building of the stages is made: a uniform one's storeys and period, or a named one's floors."""
    uniform = {building_id(n, t): {"storeys": n, "period_s": t} for n in cfg["storeys"] for t in cfg["periods_s"]}
    return {**uniform, **cfg.get("buildings", {})}


def make_building(cfg: dict, building: str) -> Building:
    spec = buildings(cfg)[building]
    if "period_s" in spec:
        return Building.uniform(spec["storeys"], spec["period_s"], cfg["zeta"])
    return Building.explicit(*(spec[key] for key in FLOOR_BY_FLOOR), zeta=cfg["zeta"])


def check_buildings(cfg: dict, section: str = "loads") -> None:
    """Every building of the stages can be made: one at least, and each named one's floors in range (named by
    its key in the configuration)."""
    if not buildings(cfg):
        raise ParameterError(f"{section}: no building: give {section}.storeys and {section}.periods_s, or "
                             f"{section}.buildings")
    for name in cfg.get("buildings", {}):
        try:
            make_building(cfg, name)
        except ParameterError as exc:
            raise ParameterError(f"{section}.buildings.{name}: {exc}") from None


def wildcard(ids) -> str:
    """The regular expression of a rule's {building} wildcard: exactly the stage's buildings."""
    return "|".join(re.escape(name) for name in ids)


def impact_damper(kind: str, building: Building, mass_ratio: float, gap: float, e: float) -> Damper:
    """An impact damper of mass_ratio x the building's mass on its roof (a pendulum tuned to its first mode)."""
    return Damper(kind, mass=mass_ratio * building.total_mass, gap=gap, e=e,
                  tuning=1.0 if kind_of(kind).spring else 0.0)
