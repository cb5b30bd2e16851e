"""The engine's two loops on the paper's cases: can the scene loop replace the paper loop?

The paper's protocol needs only the window's integral of x^2, not the certified peaks the scene loop keeps
for its monitors (roof displacement and acceleration, each storey's drift, each damper's stroke).  On the
cases of bench_core.py (the CID and the PID at g = 1, r = 1 over 500 periods, and the CID's 41-point sweep)
this times, in one process, the paper loop, the scene loop certifying every monitor's peak, and the scene loop
asked for the amplitude alone (simulate_scene's peaks=(): no peak certified), which is what the paper loop
measures.  The ratios to the paper loop decide whether one loop can serve both (the issue's bar: within 1.2x).

    python benchmarks/bench_loops.py [--quick]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from impact.engine.run import simulate_system as simulate
from impact.engine.scenes import simulate_scene
from impact.model.params import Protocol, System, frequency_grid
from impact.model.scene import paper_scene_from_system

PROTOCOL = Protocol()
PAPER = dict(mu=0.01, beta=0.0048, e=0.25)


def best_time(fun, repeats: int) -> float:
    fun()  # warm-up: compiles or loads the cache
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fun()
        times.append(time.perf_counter() - t0)
    return min(times)


def loops(systems_and_r, repeats: int) -> dict:
    scenes = [paper_scene_from_system(s, r, PROTOCOL) for s, r in systems_and_r]
    out = {
        "paper_loop": best_time(lambda: [simulate(s, r, PROTOCOL) for s, r in systems_and_r], repeats),
        "scene_loop": best_time(lambda: [simulate_scene(sc) for sc in scenes], repeats),
        "scene_loop_amplitude_alone": best_time(lambda: [simulate_scene(sc, peaks=()) for sc in scenes], repeats),
    }
    # the same physics: the window's amplitude agrees between the loops
    amp_paper = [simulate(s, r, PROTOCOL).amplitude for s, r in systems_and_r]
    amp_scene = [simulate_scene(sc, peaks=()).amplitude for sc in scenes]
    out["max_relative_amplitude_difference"] = float(np.max(np.abs(np.subtract(amp_scene, amp_paper))
                                                            / np.abs(amp_paper)))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats (numbers are noisier)")
    args = ap.parse_args(argv)
    repeats = 3 if args.quick else 15
    cid = System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER)
    pid = System.from_gap_ratio("pid", gap_ratio=1.0, rp=1.0, **PAPER)
    cases = {
        "CID, 500 periods, g = 1.0, r = 1.0": [(cid, 1.0)],
        "PID r' = 1, 500 periods, g = 1.0, r = 1.0": [(pid, 1.0)],
        "CID 41-point sweep (g = 1.0)": [(cid, float(r)) for r in frequency_grid(0.9, 1.1, 0.005)],
    }
    print(f"{'case':45s} {'paper ms':>9s} {'scene ms':>9s} {'ratio':>6s} {'amplitude ms':>13s} {'ratio':>6s}")
    for name, runs in cases.items():
        t = loops(runs, max(1, repeats // (5 if len(runs) > 1 else 1)))
        print(json.dumps({"case": name, **t}))
        print(f"{name:45s} {1e3 * t['paper_loop']:9.2f} {1e3 * t['scene_loop']:9.2f} "
              f"{t['scene_loop'] / t['paper_loop']:6.2f} {1e3 * t['scene_loop_amplitude_alone']:13.2f} "
              f"{t['scene_loop_amplitude_alone'] / t['paper_loop']:6.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
