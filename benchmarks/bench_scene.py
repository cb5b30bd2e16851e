"""Speed of the scene core on buildings under real records, measured in one process.

Cases: the 3-storey building (T1 = 1 s, zeta = 2 %) under the full El Centro
record scaled to 0.35 g, bare and with a CID (2 % of the mass) at the roof;
the same with the damper split into 4 units; a 5-storey building with a PID.
The paper's one-storey harmonic case is timed on both kernels (the
specialised one that the paper's study keeps, and the scene core), so the
ratio shows what generality costs there.  Times are the minimum of repeats
after a warm-up (the warm-up compiles); costs per segment and per impact are
printed beside them.

    python benchmarks/bench_scene.py [--quick] [--out benchmarks/results/scene.json]

Target (issue: real structures under real loads): <= 10 ms per El Centro run
of the 3-storey building with a CID.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

from impact.engine.paper import simulate
from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.params import Protocol, System
from impact.model.records import load_record
from impact.model.scene import Damper, GroundMotion, Scene, paper_scene
from impact.outputs.provenance import package_versions


def best_time(fun, repeats: int):
    out = fun()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fun()
        times.append(time.perf_counter() - t0)
    return min(times), out


def scene_case(name: str, scene: Scene, repeats: int) -> dict:
    seconds, res = best_time(lambda: simulate_scene(scene), repeats)
    d = res.diagnostics
    out = {"case": name, "ms_per_run": 1e3 * seconds, "segments": d["segments"], "impacts": d["impacts"],
           "us_per_segment": 1e6 * seconds / max(d["segments"], 1),
           "us_per_impact": 1e6 * seconds / d["impacts"] if d["impacts"] else None,
           "peak_roof_displacement": res.peak_roof_displacement, "energy_residual": d["energy_residual"]}
    print(json.dumps(out))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats (numbers are noisier)")
    ap.add_argument("--out", default="benchmarks/results/scene.json")
    args = ap.parse_args(argv)
    reps = 2 if args.quick else 7
    three = Building.uniform(3, 1.0, 0.02)
    five = Building.uniform(5, 2.0, 0.02)
    el_centro = GroundMotion.from_record(load_record("elcentro"), pga_g=0.35)
    cid = Damper("cid", 0.02 * three.total_mass, gap=0.05, e=0.5)
    cases = [
        scene_case("3 storeys, bare, El Centro 0.35 g", Scene(three, (), el_centro), reps),
        scene_case("3 storeys, CID at the roof, El Centro 0.35 g", Scene(three, (cid,), el_centro), reps),
        scene_case("3 storeys, CID in 4 units, El Centro 0.35 g",
                   Scene(three, (Damper("cid", cid.mass, gap=0.05, e=0.5, units=4),), el_centro), reps),
        scene_case("5 storeys, PID r' = 1 at the roof, El Centro 0.35 g",
                   Scene(five, (Damper("pid", 0.02 * five.total_mass, gap=0.2, e=0.5, tuning=1.0),), el_centro),
                   reps),
    ]
    # the paper's case on both kernels
    system = System.from_gap_ratio("cid", mu=0.01, beta=0.0048, e=0.25, gap_ratio=1.6)
    proto = Protocol(start="left")
    t_old, old = best_time(lambda: simulate(system, 1.0, proto), reps)
    scene = paper_scene("cid", 0.01, 0.0048, 0.25, system.gap, 1.0, start="left")
    general = scene_case("paper CID g = 1.6, left start, 500 periods (scene core)", scene, reps)
    paper = {"case": "paper CID g = 1.6, left start, 500 periods (specialised kernel)", "ms_per_run": 1e3 * t_old,
             "impacts": old.diagnostics["impacts"],
             "us_per_impact": 1e6 * t_old / old.diagnostics["impacts"],
             "scene_over_specialised": general["ms_per_run"] / (1e3 * t_old)}
    print(json.dumps(paper))
    cases += [general, paper]
    report = {"cases": cases, "machine": {"python": platform.python_version(), "processor": platform.processor(),
                                          "machine": platform.machine()}, "packages": package_versions()}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(report, indent=1) + "\n")
    print(f"\n{'case':62s} {'ms/run':>9s} {'segments':>9s} {'impacts':>8s} {'us/seg':>8s}")
    for c in cases:
        print(f"{c['case']:62s} {c['ms_per_run']:9.2f} {c.get('segments', 0):9d} {c['impacts']:8d} "
              f"{c.get('us_per_segment', float('nan')):8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
