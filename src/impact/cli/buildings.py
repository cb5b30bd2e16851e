"""Buildings from the command line: impact quake (a shear building under a ground motion, with a damper or
without), impact pushover (the exact static pushover of a yielding one) and impact records (the FEMA P695 sets)."""

from __future__ import annotations

import dataclasses
import math
import sys

import pandas as pd

from impact.cli.flags import QUAKE_DAMPER_FLAGS, QUAKE_DEFAULTS, RECORD_FORMS, TMD_DESIGNED, UNIFORM_BUILDING
from impact.cli.time_history import asked, plot
from impact.closed_form.pushover import pushover as pushover_curve
from impact.closed_form.tmd import tuned_for
from impact.engine.run import simulate
from impact.model.building import Building
from impact.model.kinds import KINDS, either
from impact.model.params import ParameterError
from impact.model.records import RecordError, kanai_tajimi
from impact.model.scene import Damper, GroundMotion, Scene
from impact.model.suites import SUITES, is_suite_key, listing, record_by_key
from impact.outputs.files import write_text_atomic


def _quake_record(args):
    """An .AT2 file, a real record's key, a FEMA P695 key, or kanai-tajimi:SOIL:SEED (a seeded synthetic record)."""
    if not args.record.startswith("kanai-tajimi:"):
        try:
            return record_by_key(args.record)
        except RecordError:
            if is_suite_key(args.record) or args.record.upper().endswith(".AT2"):
                raise  # a known form whose record is wrong: its own message says what
            raise RecordError(f"--record {args.record!r}: unknown record; give {RECORD_FORMS}") from None
    parts = args.record.split(":")
    if len(parts) != 3 or not parts[2].isdigit():
        raise RecordError(f"--record {args.record!r}: write kanai-tajimi:SOIL:SEED, e.g. kanai-tajimi:firm:7")
    duration = args.duration_s if args.duration_s is not None else 20.0
    return kanai_tajimi(int(parts[2]), duration, 0.01, soil=parts[1], pga_g=args.pga_g,
                        envelope_params=(2.0, 0.5 * duration, 0.5))


_DAMPER_FIELD = dict(gap_m="gap", e="e", rp="tuning", tuning="tuning", damping="damping", nu="nu", units="units",
                     floor="floor", stroke_limit_m="stroke_limit")


def _quake_damper_flags(args) -> dict:
    """The damper flags of --damper's kind, defaults filled in; a flag its kind does not use is refused."""
    uses = QUAKE_DAMPER_FLAGS[args.damper]
    for name in sorted({flag for kind_flags in QUAKE_DAMPER_FLAGS.values() for flag in kind_flags}):
        if getattr(args, name) is not None and name not in uses:
            users = [kind for kind, flags in QUAKE_DAMPER_FLAGS.items() if name in flags]
            raise ParameterError(f"--{name.replace('_', '-')} is not used by --damper {args.damper}: "
                                 f"it is a flag of --damper {either(users)}")
    return {name: getattr(args, name) if getattr(args, name) is not None else QUAKE_DEFAULTS.get(name)
            for name in uses}


def _quake_damper(args, flags: dict, total_mass: float):
    """The Damper the flags describe: each flag used by the kind sets its field."""

    fields = {_DAMPER_FIELD[name]: value for name, value in flags.items() if name in _DAMPER_FIELD}
    return Damper(args.damper, mass=flags["mu"] * total_mass, **fields)


def _tmd_design(args, flags: dict, building) -> dict:
    """A TMD's flags with its tuning and damping, where not given, from the study's design for the building."""
    design = tuned_for(building, flags["mu"])
    return flags | {flag: getattr(design, flag) for flag in TMD_DESIGNED if getattr(args, flag) is None}


def _building(args):
    """The building of impact quake and impact pushover (uniform, or floor by floor), yielding when
    --yield-drift-m is given."""
    building = _elastic_building(args)
    if args.hardening is not None and args.yield_drift_m is None:
        raise ParameterError("--hardening needs --yield-drift-m (an elastic storey has no post-yield branch)")
    for flag, given in (("--p-delta", args.p_delta), ("--collapse-drift-ratio", args.collapse_drift_ratio)):
        if given and args.storey_height_m is None:
            raise ParameterError(f"{flag} needs --storey-height-m")
    if args.yield_drift_m is None and not args.p_delta:
        return building
    return building.yielding(args.yield_drift_m, args.hardening or 0.0, storey_height=args.storey_height_m,
                             p_delta=args.p_delta)


def _elastic_building(args):
    explicit = (args.masses_kg, args.storey_stiffness_n_per_m)
    if explicit == (None, None):
        uniform = {flag: default if getattr(args, flag) is None else getattr(args, flag)
                   for flag, default in UNIFORM_BUILDING.items()}
        return Building.uniform(uniform["storeys"], uniform["period_s"], args.zeta,
                                floor_mass=uniform["floor_mass_kg"])
    if None in explicit:
        raise ParameterError("--masses-kg and --storey-stiffness-n-per-m go together: give both, floor 1 first")
    given = [f"--{flag.replace('_', '-')}" for flag in UNIFORM_BUILDING if getattr(args, flag) is not None]
    if given:
        raise ParameterError(f"{', '.join(given)}: a building given floor by floor (--masses-kg) has its own")
    return Building.explicit(args.masses_kg, args.storey_stiffness_n_per_m, zeta=args.zeta)


def pushover(args) -> dict:
    """The exact static pushover of a yielding uniform building: base shear against roof drift."""
    if args.yield_drift_m is None:
        raise ParameterError("pushover needs --yield-drift-m: an elastic building's curve is a straight line")
    building = _building(args)
    curve = pushover_curve(building, args.roof_drift_m, args.pattern)
    return {"building": building.as_dict(), "pattern": args.pattern, **curve.as_json()}


def quake(args) -> dict:
    """A shear building under a ground-motion record, with or without a damper at one floor."""
    record = _quake_record(args)
    building = _building(args)
    if args.floor is not None and args.floor > building.storeys:
        raise ParameterError(f"--floor = {args.floor} is out of range: allowed [1, the building's {building.storeys} "
                             "storeys]")
    flags = _quake_damper_flags(args)
    if args.damper != "none" and not KINDS[args.damper].walls:
        flags = _tmd_design(args, flags, building)
    dampers = ()
    if args.damper != "none":
        if KINDS[args.damper].walls and args.gap_m is None:
            raise ParameterError(f"--gap-m is required for --damper {args.damper}")
        dampers = (_quake_damper(args, flags, building.total_mass),)
    load = GroundMotion.from_record(record, pga_g=args.pga_g)
    scene = Scene(building, dampers, load, duration=args.duration_s, start=flags.get("start", "centre"),
                  collapse_drift_ratio=args.collapse_drift_ratio, max_events=args.max_events)
    if (args.plot or args.compare_bare) and not dampers:
        flag = "--plot draws a damper's strokes and impacts" if args.plot else "--compare-bare compares a damper"
        raise ParameterError(f"{flag}: give --damper {either(KINDS)}")
    plotted = asked(scene, ("amplitude", "impacts", "peaks"),
                     building.period1 / 50 if args.plot or args.series else None)
    res = simulate(scene, **plotted)
    bare = None
    if args.plot or args.compare_bare:
        bare = simulate(dataclasses.replace(scene, dampers=()), **plotted)  # the same scene and measures, bare
    if args.plot:
        plot(args.plot, scene, res, f"impact {' '.join(sys.argv[1:])}", "m", "N s",
              roof_bare=bare.samples["q"][:, building.storeys - 1])
    if args.series:
        _write_series(args.series, scene, res)
    out = {"record": {"name": record.name, "source": record.source, "dt_s": record.dt, "npts": record.npts,
                      "pga_g": load.pga / 9.80665, **({"metadata": record.metadata} if record.metadata else {})},
           "building": building.as_dict(), "damper": args.damper,
           "dampers": [dict(vars(d)) for d in dampers]}
    out.update(res.as_json("m"))
    if args.compare_bare:
        out["bare"] = {key: bare_value for key, bare_value in bare.as_json("m").items() if key in COMPARED}
        out["ratio_to_bare"] = {key: out[key] / bare_value if bare_value else math.nan
                                for key, bare_value in out["bare"].items()}
    return out


#: what --compare-bare reports of the bare building, and as the ratio of the damped building's to it
COMPARED = ("peak_roof_displacement_m", "rms_roof_displacement_m", "peak_roof_acceleration_ms2",
            "peak_interstorey_drift_m")


def _write_series(path: str, scene, res) -> None:
    """The run's time series as CSV: each floor's displacement relative to the ground and each damper unit's
    stroke relative to its floor, in metres, at the samples --plot draws."""
    q, storeys = res.samples["q"], scene.building.storeys
    columns = {"t_s": res.samples["t"]}
    columns.update({f"floor{i + 1}_m": q[:, i] for i in range(storeys)})
    unit = storeys
    for d, damper in enumerate(scene.dampers, start=1):
        floor = scene.floor_index(damper.floor)
        for j in range(damper.units):
            columns[f"damper{d}_unit{j + 1}_stroke_m"] = q[:, unit] - q[:, floor]
            unit += 1
    write_text_atomic(path, pd.DataFrame(columns).to_csv(index=False, float_format="%.9g"))


def records(args) -> dict:
    """The ground motions of the FEMA P695 suites: each key (for impact quake --record), its group and record."""
    suites = list(SUITES) if args.suite == "all" else [args.suite]
    return {suite: listing(suite) for suite in suites}
