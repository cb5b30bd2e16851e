"""The incremental dynamic analysis's plan: buildings, dampers, ground motions and the Sa(T1) ladder, from the
configuration.  Nothing here runs the engine."""

from __future__ import annotations

from impact.model.params import ParameterError
from impact.model.records import RecordError
from impact.model.scene import DAMPER_KINDS
from impact.model.suites import is_suite_key, parse_key, suite_keys
from impact.outputs.labels import RUN_MEASURES
from impact.stages.buildings import buildings

#: the cases of one building: the bare building, then each damper type
KINDS = ("bare", *DAMPER_KINDS)
#: the section's keys only the dampers' designs read (their clearance's level, their stroke limit): a change of one
#: reruns the damper runs, not the bare ones
DESIGN_KEYS = ("design_sa_g", "stroke_limit_m")
#: how near the stroke limit a certified peak stroke counts as reaching it, relative: far above a stop's contact
#: tolerance, the peak's round-off (1e-12 of it) and a linear run's scaling (tested exact to 1e-12)
AT_LIMIT = 1e-9


def scales_linearly(building, dampers: tuple) -> bool:
    """Whether a case's response is linear in the level, so that one run at Sa(T1) = 1 g scales to every level: an
    elastic building whose dampers never strike (none has walls or end stops).  A building that yields or feels
    P-delta is run at every level."""
    return building.is_elastic and not any(d.has_walls for d in dampers)


def motions(cfg: dict) -> list[str]:
    """The ground motions of the stage: the keys asked, or every ground motion of the suites asked."""
    return list(cfg["motions"]) or [key for suite in cfg["suites"] for key in suite_keys(suite)]


def ladder(cfg: dict) -> list[float]:
    return [float(level) for level in cfg["sa_g"]]


def check_config(cfg: dict, loads: dict | None) -> None:
    """Checks of the ida section a JSON schema cannot express; the message names the key."""
    if not loads:
        raise ParameterError("ida: the stage runs on the earthquake study's buildings and damper designs, so it needs "
                             "the loads section configured and not skipped")
    levels = ladder(cfg)
    if not levels:
        raise ParameterError("ida.sa_g is empty: give the ladder of Sa(T1) levels in g, e.g. [0.1, 0.5, 1.0]")
    if sorted(set(levels)) != levels:
        raise ParameterError(f"ida.sa_g = {levels} must rise strictly: each level once, lowest first")
    if cfg["design_sa_g"] not in levels:
        raise ParameterError(f"ida.design_sa_g = {cfg['design_sa_g']} must be one of ida.sa_g = {levels}")
    for key in cfg["motions"]:
        if not is_suite_key(key):
            raise ParameterError(f"ida.motions: {key!r} is not a FEMA P695 key (fema-<suite>:<record id>:<a|b>)")
        try:
            parse_key(key)
        except RecordError as exc:
            raise ParameterError(f"ida.motions: {exc}") from None
    if len(set(motions(cfg))) != len(motions(cfg)):
        raise ParameterError("ida.motions names a ground motion twice")


def stage_buildings(loads: dict) -> list[str]:
    return list(buildings(loads))


#: measure -> (long name, units); the first four (SCALED) are linear in the level for a linear building and damper
MEASURES = {
    "drift_ratio": ("peak inter-storey drift ratio (drift over the storey height)", "1"),
    "peak_roof": ("peak roof displacement relative to the ground", "m"),
    **RUN_MEASURES,
}
SCALED = ("drift_ratio", "peak_roof", "peak_accel", "stroke")
#: the measures that are counts or flags (stored as integers); a flag (units None) has meanings instead
WHOLE = ("impacts", "event_cap_reached")
