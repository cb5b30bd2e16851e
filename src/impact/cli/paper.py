"""The paper's model from the command line: impact run (one run under the response protocol), impact sweep (one
frequency sweep) and impact masri (Masri's closed form)."""

from __future__ import annotations

import math
import sys

from impact.cli.time_history import asked, plot
from impact.closed_form.masri import masri_2eipc
from impact.engine.run import simulate, sweep
from impact.model.kinds import KINDS, either, kinds_with
from impact.model.params import ParameterError, Protocol, System, a_max, frequency_grid, ipc_label
from impact.model.scene import paper_scene_from_system
from impact.outputs.datasets import curve_dataset
from impact.outputs.files import write_dataset


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


def run(args) -> dict:
    """One run of the paper's structure; with --units N > 1 the damper is N units of mass mu/N, gap d each.

    The engine picks the loop (impact.engine.run.LOOPS): the paper loop for one unit, the scene loop for more.
    """
    system = _system(args)
    scene = paper_scene_from_system(system, args.r, _protocol(args), units=args.units)
    res = simulate(scene, **asked(scene, ("amplitude", "impacts"), 2.0 * math.pi / args.r / 20 if args.plot else None))
    if args.plot:
        plot(args.plot, scene, res, f"impact {' '.join(sys.argv[1:])}", "1", "1")
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


#: impact sweep's per-frequency lists, which --out writes to its dataset instead of printing
PER_FREQUENCY = ("r", "amplitude", "amplitude_ratio", "aipc", "ipc_class")


def run_sweep(args) -> dict:
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
        ds = curve_dataset(system, [args.gap_ratio], [protocol.start], [[result]], protocol,
                           curve={"command": "impact " + " ".join(sys.argv[1:])})
        write_dataset(ds, args.out)
        out = {key: value for key, value in out.items() if key not in PER_FREQUENCY} | {"out": args.out}
    return out


def masri(args) -> dict:
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
