"""The exact core against scipy's solve_ivp (DOP853, event location, rtol 1e-10).

Same cases, same process, same machine: a 500-period CID run with impacts, a
500-period PID run, and a 41-point CID frequency sweep.  Wall time is the
minimum of several repeats after a warm-up (numba compiles on the warm-up).
Each method's error is measured against a tight reference, solve_ivp DOP853 at
rtol 1e-13: the amplitude (sqrt(2) RMS over the window), and the times of the
first 50 impacts.  For the sweep the reference is run only at the frequency
of x_max (a full reference sweep takes about half an hour).

    python benchmarks/bench_core.py [--quick] [--out benchmarks/results/core_vs_ivp.json]

Targets (issue: exact event-driven core): >= 200x faster than solve_ivp at
equal or better accuracy; a 41-point CID sweep with impacts in <= 0.25 s.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from impact.baselines.ivp import simulate_ivp
from impact.engine.run import simulate_system as simulate
from impact.engine.run import sweep
from impact.model.params import Protocol, System, frequency_grid
from impact.outputs.provenance import package_versions

PROTOCOL = Protocol()
K_IMPACTS = 50


def best_time(fun, repeats: int) -> tuple[float, object]:
    out = fun()  # warm-up (compilation for the core)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fun()
        times.append(time.perf_counter() - t0)
    return min(times), out


def ivp(system, r, rtol):
    return simulate_ivp(system, r, PROTOCOL.t_end, PROTOCOL.t_window, PROTOCOL.start, method="DOP853", rtol=rtol)


def run_case(name, system, r, repeats_core, repeats_ivp) -> dict:
    t_core, core = best_time(lambda: simulate(system, r, PROTOCOL, record=K_IMPACTS), repeats_core)
    t_ivp, base = best_time(lambda: ivp(system, r, 1e-10), repeats_ivp)
    ref = ivp(system, r, 1e-13)
    k = min(K_IMPACTS, len(ref.impact_times), len(core.records["t"]), len(base.impact_times))
    out = {
        "case": name,
        "impacts": core.diagnostics["impacts"],
        "core_seconds": t_core,
        "core_us_per_impact": 1e6 * t_core / max(core.diagnostics["impacts"], 1),
        "ivp_seconds": t_ivp,
        "speedup": t_ivp / t_core,
        "core_amplitude_error": abs(core.amplitude - ref.amplitude) / ref.amplitude,
        "ivp_amplitude_error": abs(base.amplitude - ref.amplitude) / ref.amplitude,
        "core_impact_time_error": float(np.max(np.abs(core.records["t"][:k] - ref.impact_times[:k]))) if k else None,
        "ivp_impact_time_error": float(np.max(np.abs(base.impact_times[:k] - ref.impact_times[:k]))) if k else None,
        "ivp_nfev": int(base.nfev),
    }
    print(json.dumps(out))
    return out


def run_sweep(system, repeats_core) -> dict:
    grid = frequency_grid(0.9, 1.1, 0.005)
    t_core, core = best_time(lambda: sweep(system, grid, PROTOCOL), repeats_core)
    t0 = time.perf_counter()
    base = [ivp(system, float(r), 1e-10) for r in grid]
    t_ivp = time.perf_counter() - t0
    x_ivp = max(b.amplitude for b in base)
    r_max = core.r_at_max
    ref = ivp(system, r_max, 1e-13)
    out = {
        "case": "CID 41-point sweep (g = 1.0)",
        "impacts": int(core.column("impacts").sum()),
        "core_seconds": t_core,
        "core_us_per_impact": 1e6 * t_core / max(int(core.column("impacts").sum()), 1),
        "ivp_seconds": t_ivp,
        "speedup": t_ivp / t_core,
        "core_amplitude_error": abs(core.x_max - ref.amplitude) / ref.amplitude,
        "ivp_amplitude_error": abs(x_ivp - ref.amplitude) / ref.amplitude,
        "r_at_max": r_max,
        "ivp_nfev": int(sum(b.nfev for b in base)),
    }
    print(json.dumps(out))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats (numbers are noisier)")
    ap.add_argument("--out", default="benchmarks/results/core_vs_ivp.json")
    args = ap.parse_args(argv)
    rc, ri = (3, 1) if args.quick else (20, 3)
    paper = dict(mu=0.01, beta=0.0048, e=0.25)
    cases = [
        run_case("CID, 500 periods, g = 1.0, r = 1.0", System.from_gap_ratio("cid", gap_ratio=1.0, **paper), 1.0, rc, ri),
        run_case("PID r' = 1, 500 periods, g = 1.0, r = 1.0",
                 System.from_gap_ratio("pid", gap_ratio=1.0, rp=1.0, **paper), 1.0, rc, ri),
        run_sweep(System.from_gap_ratio("cid", gap_ratio=1.0, **paper), rc),
    ]
    report = {"cases": cases, "machine": {"python": platform.python_version(), "processor": platform.processor(),
                                          "machine": platform.machine()}, "packages": package_versions()}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(report, indent=1) + "\n")
    print(f"{'case':45s} {'core ms':>9s} {'us/impact':>9s} {'ivp s':>9s} {'speedup':>9s} {'core err':>9s} "
          f"{'ivp err':>9s}")
    for c in cases:
        print(f"{c['case']:45s} {1e3 * c['core_seconds']:9.2f} {c['core_us_per_impact']:9.2f} "
              f"{c['ivp_seconds']:9.2f} {c['speedup']:9.0f} {c['core_amplitude_error']:9.1e} "
              f"{c['ivp_amplitude_error']:9.1e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
