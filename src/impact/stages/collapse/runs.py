"""The collapse assessment's runs on the exact engine: per archetype and case, every ground motion traced to collapse
by hunt and fill (Vamvatsikos & Cornell 2004)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from impact.engine.run import simulate
from impact.model.building import Building
from impact.model.params import G_GRAV
from impact.model.records import Record
from impact.model.scene import GroundMotion, Scene
from impact.model.suites import load_suite_record
from impact.outputs.files import as_integers, flag
from impact.outputs.labels import EVENT_CAP_MEANINGS
from impact.stages.collapse.p695 import archetype_numbers
from impact.stages.collapse.plan import archetype, code_period, hunt_levels, stability_limit
from impact.stages.ida.runs import STROKE_LIMIT_ATTRS, design_peak, designed_damper, scaled_motion

INITIAL_CONDITION = ("building at rest with no plastic drift; an impact damper's mass centred between its walls; "
                     "every run of a ground motion starts so")

#: what each run keeps: name -> (long name, units; None: a flag)
RUN_MEASURES = {
    "run_sa": ("Sa(T1, 5 %) the ground motion is scaled to in this run, over standard gravity (Sa in g)", "1"),
    "run_drift_ratio": ("peak inter-storey drift ratio of the run (up to the collapse, if it collapsed)", "1"),
    "run_collapsed": ("whether a storey's drift reached the collapse limit", None),
    "run_energy_residual": ("energy balance residual of the run, relative", "1"),
    "run_event_cap_reached": ("whether the run stopped at the event cap or the stall guard", None),
    "run_impacts": ("impacts of the damper's units in the run", "1"),
}
HUNT_UP = "up the hunt's levels from the first (collapse.hunt)"
HUNT_FROM_BARE = ("from the bare archetype's bracket of the motion, stepping away from it until the outcome turns "
                  "(up the hunt's levels where the bare archetype found none)")
FLAGS = {"run_collapsed": ("stood", "collapsed"), "run_event_cap_reached": EVENT_CAP_MEANINGS}
WHOLE = ("run_collapsed", "run_event_cap_reached", "run_impacts", "runs", "unresolved")


@dataclass
class Trace:
    """One ground motion's runs in the order they ran, and the bracket the collapse intensity lies in (g):
    `standing` the highest Sa below the collapse that stood, `collapse` the lowest that collapsed (None: none up
    to the hunt's last level, or none before the trace stopped).  `unresolved`: a run stopped at the event cap or
    the stall guard, and the trace with it, the bracket as it stood then."""

    runs: list = field(default_factory=list)
    standing: float = 0.0
    collapse: float | None = None
    unresolved: bool = False


class _Unresolved(Exception):
    """A run stopped at the event cap or the stall guard: it says neither that the building stood nor that it fell."""


def with_free_vibration(record: Record, sa_record_g: float, level_g: float, free_s: float) -> GroundMotion:
    """The record scaled so that its Sa(T1) is level_g, then `free_s` seconds of still ground: a drift running
    away when the shaking stops still reaches its limit."""
    motion = scaled_motion(record, sa_record_g, level_g)
    tail = np.zeros(int(round(free_s / record.dt)))
    return GroundMotion(np.concatenate([motion.accel, tail]), motion.dt, motion.name)


def collapse_run(building: Building, dampers: tuple, motion: GroundMotion, drift_limit: float | None) -> dict:
    """One run to the end of the motion or to collapse: its measures."""
    res = simulate(Scene(building, dampers, motion, collapse_drift_ratio=drift_limit), measures=("impacts", "drifts"))
    heights = building.storey_height
    collapsed = res.storeys is not None and res.storeys.collapsed
    return {"run_drift_ratio": float(np.max(res.peak_drifts / heights)), "run_collapsed": int(collapsed),
            "run_energy_residual": res.diagnostics["energy_residual"],
            "run_event_cap_reached": int(bool(res.diagnostics["event_cap_reached"])), "run_impacts": res.impacts}


def trace(run_at, cfg: dict, reference: Trace | None = None) -> Trace:
    """Hunt: the hunt's levels up to the first collapse (halving down from the first level if it collapses), or,
    given a `reference` trace of the same motion that found a collapse (the bare archetype's), its bracket's ends
    first, stepping away from them by growing steps until the outcome turns.  Bisect the bracket until it is
    narrower than `resolution` of its top.  Fill: the widest gaps below the bracket get a run each, `fill` times,
    so the drift curve is drawn where it climbs; a fill run that collapses (a curve that resurrects above it)
    becomes the collapse, and its bracket is bisected in turn.  A run that stops at the event cap ends the trace,
    flagged."""
    out = Trace()

    def collapses(level: float) -> bool:
        out.runs.append({"run_sa": level, **run_at(level)})
        if out.runs[-1]["run_event_cap_reached"]:
            raise _Unresolved
        return bool(out.runs[-1]["run_collapsed"])

    try:
        if _has_bracket(reference):
            _hunt_from(out, collapses, cfg, reference)
        else:
            _hunt_fill(out, collapses, cfg)
    except _Unresolved:
        out.unresolved = True
    return out


def _has_bracket(reference: Trace | None) -> bool:
    """Whether a reference trace ended on a bracket a hunt may start from: a collapse with a level standing below."""
    return (reference is not None and not reference.unresolved and reference.collapse is not None
            and reference.standing > 0.0)


def _hunt_fill(out: Trace, collapses, cfg: dict) -> None:
    for level in hunt_levels(cfg["hunt"]):
        if collapses(level):
            out.collapse = level
            break
        out.standing = level
    if out.collapse is None:
        return
    if out.standing == 0.0 and not _step_down(out, collapses, 0.5 * out.collapse, 0.5):
        return
    _narrow_and_fill(out, collapses, cfg)


def _narrow_and_fill(out: Trace, collapses, cfg: dict) -> None:
    _narrow(out, collapses, cfg["resolution"])
    for _ in range(cfg["fill"]):
        _fill_widest_gap(out, collapses, cfg["resolution"])


def _hunt_from(out: Trace, collapses, cfg: dict, reference: Trace) -> None:
    """The hunt started at a reference's bracket: a damper of a few per cent of the building's mass moves a motion's
    collapse intensity by little, so its ends are the likeliest bracket.  Where the outcome there differs, the level
    steps away by `resolution`, twice that, four times, ... of the last (down, at most halving; up, to the hunt's
    top), until it turns.  The bracket found is a stand below a collapse, as the hunt's, narrowed and filled alike."""
    if collapses(reference.collapse):
        out.collapse = reference.collapse
        if not _step_down(out, collapses, reference.standing, cfg["resolution"]):
            return
    else:
        out.standing = reference.collapse
        if not _step_up(out, collapses, cfg["resolution"], cfg["hunt"]["max_sa_g"]):
            return
    _narrow_and_fill(out, collapses, cfg)


def _step_down(out: Trace, collapses, level: float, step: float) -> bool:
    """From `level` down, each step twice the last (a halving at most), until a run stands; False if none does
    within HALVINGS runs more than the steps to a halving take (the bracket is then [0, lowest]).  From the first
    hunt level a collapse halves at once (step 0.5): HALVINGS halvings."""
    for _ in range(HALVINGS + math.ceil(math.log2(0.5 / step))):
        if not collapses(level):
            out.standing = level
            return True
        out.collapse = level
        level *= 1.0 - step
        step = min(2.0 * step, 0.5)
    return False


def _step_up(out: Trace, collapses, step: float, top: float) -> bool:
    """From the standing level up, each step twice the last, to the hunt's top at most, until a run collapses;
    False if the top stands (no collapse, as the hunt's)."""
    while out.standing < top:
        level = min(out.standing * (1.0 + step), top)
        if collapses(level):
            out.collapse = level
            return True
        out.standing = level
        step *= 2.0
    return False


#: halvings below the first hunt level before a motion is said to collapse below what the study resolves
HALVINGS = 6


#: bisections at most: a bracket from 0 (no level below the collapse stood) narrows as a halving does, so this bounds
#: the trace where it would chase a collapse towards zero; from any bracket the hunt leaves, ~10 suffice
BISECTIONS = 40


def _narrow(out: Trace, collapses, resolution: float) -> None:
    for _ in range(BISECTIONS):
        if out.collapse - out.standing <= resolution * out.collapse:
            return
        middle = 0.5 * (out.standing + out.collapse)
        if collapses(middle):
            out.collapse = middle
        else:
            out.standing = middle


def _fill_widest_gap(out: Trace, collapses, resolution: float) -> None:
    below = sorted({0.0, *(r["run_sa"] for r in out.runs if r["run_sa"] <= out.standing)})
    gaps = np.diff(below)
    widest = int(np.argmax(gaps))
    if not collapses(0.5 * (below[widest] + below[widest + 1])):
        return
    out.collapse = out.runs[-1]["run_sa"]
    out.standing = max((r["run_sa"] for r in out.runs if r["run_sa"] < out.collapse and not r["run_collapsed"]),
                       default=0.0)
    _narrow(out, collapses, resolution)


def _traces_dataset(traces: list[Trace], keys: list[str]) -> xr.Dataset:
    """Per ground motion: its runs sorted by level (padded with NaN to the most any motion took) and its bracket."""
    width = max(len(t.runs) for t in traces)
    data = {}
    for name in RUN_MEASURES:
        table = np.full((len(traces), width), np.nan)
        for i, t in enumerate(traces):
            ordered = sorted(t.runs, key=lambda r: r["run_sa"])
            table[i, :len(ordered)] = [r[name] for r in ordered]
        data[name] = (("motion", "run"), table)
    data["collapse_sa"] = ("motion", np.array([np.nan if t.collapse is None else t.collapse for t in traces]))
    data["standing_sa"] = ("motion", np.array([t.standing for t in traces]))
    data["runs"] = ("motion", np.array([len(t.runs) for t in traces]))
    data["unresolved"] = ("motion", np.array([int(t.unresolved) for t in traces]))
    return xr.Dataset(data, coords={"motion": keys, "run": np.arange(width)})


def _motions(ida_bare: xr.Dataset) -> tuple[list[str], dict[str, Record], dict[str, float]]:
    keys = ida_bare["motion"].values.tolist()
    return keys, {k: load_suite_record(k) for k in keys}, dict(zip(keys, ida_bare["sa_record"].values.tolist()))


def traced(cfg: dict, building: Building, dampers: tuple, ida_bare: xr.Dataset,
           reference: xr.Dataset | None = None) -> xr.Dataset:
    """Every ground motion of the linear IDA's set traced to collapse on one archetype with its dampers, each from
    its bracket in `reference` (the bare archetype's traces) where that found one."""
    keys, records, sa = _motions(ida_bare)
    brackets = _brackets_of(reference, keys)
    traces = [trace(lambda level, key=key: collapse_run(
        building, dampers, with_free_vibration(records[key], sa[key], level, cfg["free_vibration_s"]),
        cfg["drift_limit"]), cfg, brackets[key]) for key in keys]
    return _traces_dataset(traces, keys).assign_coords(group=ida_bare["group"])


def _brackets_of(reference: xr.Dataset | None, keys: list[str]) -> dict[str, Trace | None]:
    """Each motion's bracket as a reference trace found it (its runs are not needed)."""
    if reference is None:
        return dict.fromkeys(keys)
    ref = reference.sel(motion=keys)
    collapse = [None if np.isnan(c) else float(c) for c in ref["collapse_sa"].values]
    return {key: Trace(standing=float(s), collapse=c, unresolved=bool(u)) for key, s, c, u in
            zip(keys, ref["standing_sa"].values, collapse, ref["unresolved"].values)}


def _pushover_dataset(numbers: dict, building: Building, theta_max: float) -> xr.Dataset:
    curve = numbers["curve"]
    ds = xr.Dataset({
        "pushover_roof_drift": ("corner", curve.roof_drift,
                                {"long_name": "pushover: roof drift relative to the ground", "units": "m"}),
        "pushover_base_shear": ("corner", curve.base_shear / (building.total_mass * G_GRAV),
                                {"long_name": "pushover: base shear over the building's weight", "units": "1"}),
        "yield_drift": ("storey", building.yield_drift,
                        {"long_name": "storey drift at first yield (design strength over elastic stiffness)",
                         "units": "m"}),
        "storey_strength": ("storey", building.yield_drift * building.storey_stiffness,
                            {"long_name": "storey shear strength by the design rule", "units": "N"}),
        "stability_coefficient": ("storey", building.stability_coefficients(),
                                  {"long_name": "P-delta stability coefficient theta: weight carried over elastic "
                                                "stiffness times storey height", "units": "1"}),
    }, coords={"storey": np.arange(1, building.storeys + 1)})
    ds["storey"].attrs = {"long_name": "storey, from the ground up", "units": "1"}
    ds.attrs.update({key: numbers[key] for key in ("period_s", "code_period_s", "period_p_delta_s", "v_max_over_w",
                                                   "c0", "yield_roof_drift_m", "ultimate_roof_drift_m", "ultimate_by",
                                                   "mu_T", "S_MT_g")},
                    pushover_ended=curve.ended, stability_limit=theta_max)
    return ds


def _described(ds: xr.Dataset, cfg: dict, building_name: str, building: Building, case: str) -> xr.Dataset:
    for name, (text, units) in RUN_MEASURES.items():
        ds[name].attrs = flag(text, *FLAGS[name]) if units is None else {"long_name": text, "units": units}
    ds["collapse_sa"].attrs = {"long_name": "collapse intensity: the lowest Sa(T1, 5 %) found to collapse, over "
                                            "standard gravity (NaN: none up to the hunt's last level)", "units": "1"}
    ds["standing_sa"].attrs = {"long_name": "the highest Sa(T1, 5 %) below the collapse intensity found to stand, "
                                            "over standard gravity", "units": "1"}
    ds["runs"].attrs = {"long_name": "runs the ground motion took", "units": "1"}
    ds["unresolved"].attrs = flag("whether a run of the ground motion stopped at the event cap or the stall guard, "
                                  "ending its trace (censored at standing_sa)", "resolved", "unresolved")
    ds = as_integers(ds, WHOLE, missing=-1)
    ds["motion"].attrs = {"long_name": "FEMA P695 ground motion (suite:record:component)"}
    ds["group"].attrs = {"long_name": "record group (far-field, near-field pulse, near-field no pulse)"}
    ds["run"].attrs = {"long_name": "run of a ground motion, by its level (lowest first)", "units": "1"}
    ds.attrs.update(title=f"Collapse assessment: archetype {building_name}, {case}", building=building_name,
                    damper=case, storeys=building.storeys, period1_s=building.period1, zeta=building.zeta,
                    hardening=building.hardening, drift_limit=cfg["drift_limit"], resolution=cfg["resolution"],
                    free_vibration_s=cfg["free_vibration_s"], initial_condition=INITIAL_CONDITION)
    return ds


def bare_collapse(cfg: dict, ida: dict, loads: dict, building_name: str, ida_bare: xr.Dataset) -> xr.Dataset:
    """The bare archetype: its design, its pushover and P695's numbers from it, every motion traced to collapse."""
    building = archetype(cfg, ida, loads, building_name)
    numbers = archetype_numbers(building, cfg, code_period(cfg, building.storey_height))
    ds = xr.merge([traced(cfg, building, (), ida_bare), _pushover_dataset(numbers, building, stability_limit(cfg))],
                  combine_attrs="no_conflicts")
    return _described(ds, cfg, building_name, building, "bare").assign_attrs(hunt=HUNT_UP)


def damper_collapse(cfg: dict, ida: dict, loads: dict, building_name: str, kind: str, ida_bare: xr.Dataset,
                    gap_ratios: dict[float, float], bare: xr.Dataset) -> xr.Dataset:
    """One damper type at each mass ratio, as the linear IDA designs it, on the archetype, traced to collapse, each
    motion's hunt started at the `bare` archetype's bracket (`trace`)."""
    building = archetype(cfg, ida, loads, building_name)
    peak = design_peak(ida_bare, ida["design_sa_g"])
    designs = [designed_damper(loads, ida, building, kind, mr, gap_ratios, peak) for mr in loads["mass_ratios"]]
    parts = [traced(cfg, building, (damper,), ida_bare, bare) for damper in designs]
    ds = xr.concat(parts, dim="mass_ratio", join="outer", coords="minimal",
                   compat="override").assign_coords(mass_ratio=list(loads["mass_ratios"]))
    ds["mass_ratio"].attrs = {"long_name": "damper mass over the building's total mass", "units": "1"}
    ds["clearance"] = ("mass_ratio", [d.clearance for d in designs],
                       {"long_name": "distance between a damper unit's walls or end stops (0: none)", "units": "m"})
    if ida["stroke_limit_m"] is not None:
        ds["stroke_limit"] = ((), ida["stroke_limit_m"], STROKE_LIMIT_ATTRS)
    return _described(ds, cfg, building_name, building, kind).assign_attrs(hunt=HUNT_FROM_BARE)
