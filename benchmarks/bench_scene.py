"""Speed of the scene core on buildings under real records, measured in one process.

Cases: the 3-storey building (T1 = 1 s, zeta = 2 %) under the full El Centro
record scaled to 0.35 g, bare and with a CID (2 % of the mass) at the roof;
the same with the damper split into 4 units; a 5-storey building with a PID.
The paper's one-storey harmonic case is timed on both kernels (the
specialised one that the paper's study keeps, and the scene core, with every
peak certified and with the amplitude alone, which is all the paper loop
measures), so the ratio shows what generality costs there.  The CID case is
also timed certifying the drifts' peaks alone, as the collapse stage asks.
Times are the minimum of repeats after a warm-up (the warm-up compiles); costs
per segment and per impact are printed beside them.

    python benchmarks/bench_scene.py [--quick] [--out benchmarks/results/scene.json]

Beside the scene core on the bare 1- and 3-storey buildings: the same buildings under the same record by a
compiled exact discrete propagator (x_{k+1} = A x_k + B0 a_k + B1 a_{k+1}, the matrix exponential with a
first-order hold, exact for a piecewise-linear record; peaks sampled at the record's steps, not certified), the
floor a sample's cost could reach; and OpenSees' linear Newmark (average acceleration) at the record's step on
the 3-storey building, the peer's cost for the same run (skipped, and said so, without openseespy).

Target (issue: real structures under real loads): <= 10 ms per El Centro run
of the 3-storey building with a CID.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np
from numba import njit

from impact.closed_form.propagator import first_order_hold
from impact.engine.run import simulate_system as simulate
from impact.engine.scenes import PEAK_GROUPS, simulate_scene
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


@njit(cache=True)
def propagate(a_mat, b0, b1, accel, roof):
    """The peak |q_roof| over the record's samples, from rest."""
    x = np.zeros(a_mat.shape[0])
    y = np.empty_like(x)
    peak = 0.0
    for k in range(accel.shape[0] - 1):
        for i in range(x.shape[0]):
            acc = b0[i] * accel[k] + b1[i] * accel[k + 1]
            for j in range(x.shape[0]):
                acc += a_mat[i, j] * x[j]
            y[i] = acc
        x[:] = y
        peak = max(peak, abs(x[roof]))
    return peak


def propagator_case(name: str, building: Building, gm: GroundMotion, repeats: int) -> dict:
    a_mat, b0, b1 = first_order_hold(building, gm.dt)
    seconds, peak = best_time(lambda: propagate(a_mat, b0, b1, gm.accel, building.storeys - 1), repeats)
    out = {"case": name, "ms_per_run": 1e3 * seconds, "impacts": 0, "samples": len(gm.accel),
           "ns_per_sample": 1e9 * seconds / len(gm.accel), "peak_roof_displacement": peak}
    print(json.dumps(out))
    return out


def opensees_case(name: str, building: Building, gm: GroundMotion) -> dict | None:
    """OpenSees' linear Newmark (average acceleration) at the record's step: one run, the analysis loop timed."""
    try:
        import openseespy.opensees as ops
    except ImportError:
        print(json.dumps({"case": name, "skipped": "openseespy is not installed (make peer installs it)"}))
        return None
    n = building.storeys
    ops.wipe()
    ops.logFile("/dev/null", "-noEcho")  # the full eigensolver's warning that it is slow (it is not, for n modes)
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(0, 0.0)
    ops.fix(0, 1)
    for i in range(1, n + 1):
        ops.node(i, 0.0)
        ops.mass(i, float(building.masses[i - 1]))
        ops.uniaxialMaterial("Elastic", i, float(building.storey_stiffness[i - 1]))
        ops.element("zeroLength", i, i - 1, i, "-mat", i, "-dir", 1)
    # the engine's damping: the same ratio in every mode (every mode of the model: the full eigensolver)
    ops.eigen("-fullGenLapack", n)
    ops.modalDamping(building.zeta)
    ops.timeSeries("Path", 1, "-dt", gm.dt, "-values", *gm.accel.tolist())
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("BandGeneral")
    ops.algorithm("Linear")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    steps = len(gm.accel) - 1
    peak = 0.0
    t0 = time.perf_counter()
    for _ in range(steps):
        ops.analyze(1, gm.dt)
        peak = max(peak, abs(ops.nodeDisp(n, 1)))
    seconds = time.perf_counter() - t0
    ops.wipe()
    out = {"case": name, "ms_per_run": 1e3 * seconds, "impacts": 0, "peak_roof_displacement": peak}
    print(json.dumps(out))
    return out


def scene_case(name: str, scene: Scene, repeats: int, peaks=PEAK_GROUPS, window: bool = True) -> dict:
    seconds, res = best_time(lambda: simulate_scene(scene, peaks=peaks, window=window), repeats)
    d = res.diagnostics
    out = {"case": name, "ms_per_run": 1e3 * seconds, "segments": d["segments"], "clear_steps": d["clear_steps"],
           "impacts": d["impacts"], "us_per_segment": 1e6 * seconds / max(d["segments"], 1),
           "us_per_impact": 1e6 * seconds / d["impacts"] if d["impacts"] else None,
           "peak_roof_displacement": res.peak_roof_displacement, "energy_residual": d["energy_residual"]}
    print(json.dumps(out))
    return out


def record_scenes() -> dict:
    """The scene-core cases under El Centro: {name: (scene, the peaks certified, whether the window is read)}; the
    exact propagator's cases run the bare buildings of the names that say "bare" (tools/engine_profile.py profiles
    these too)."""
    one = Building.uniform(1, 1.0, 0.02)
    three = Building.uniform(3, 1.0, 0.02)
    five = Building.uniform(5, 2.0, 0.02)
    el_centro = GroundMotion.from_record(load_record("elcentro"), pga_g=0.35)
    cid = Damper("cid", 0.02 * three.total_mass, gap=0.05, e=0.5)
    return {
        "1 storey, bare, El Centro 0.35 g, scene core": (Scene(one, (), el_centro), PEAK_GROUPS, True),
        "3 storeys, bare, El Centro 0.35 g, scene core": (Scene(three, (), el_centro), PEAK_GROUPS, True),
        "3 storeys, CID at the roof, El Centro 0.35 g": (Scene(three, (cid,), el_centro), PEAK_GROUPS, True),
        # what the collapse stage asks of a run: the drifts' peaks alone, no window
        "3 storeys, CID at the roof, El Centro 0.35 g, drifts alone": (Scene(three, (cid,), el_centro), ("drifts",),
                                                                       False),
        "3 storeys, CID in 4 units, El Centro 0.35 g": (
            Scene(three, (Damper("cid", cid.mass, gap=0.05, e=0.5, units=4),), el_centro), PEAK_GROUPS, True),
        "5 storeys, PID r' = 1 at the roof, El Centro 0.35 g": (
            Scene(five, (Damper("pid", 0.02 * five.total_mass, gap=0.2, e=0.5, tuning=1.0),), el_centro),
            PEAK_GROUPS, True),
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats (numbers are noisier)")
    ap.add_argument("--out", default="benchmarks/results/scene.json")
    args = ap.parse_args(argv)
    reps = 2 if args.quick else 7
    cases = []
    scenes = record_scenes()
    for name, (scene, peaks, window) in scenes.items():
        if "bare" in name:  # the same building by the exact propagator first
            size = name.split(",")[0]
            cases.append(propagator_case(f"{size}, bare, El Centro 0.35 g, exact propagator", scene.building,
                                         scene.load, reps))
        cases.append(scene_case(name, scene, reps, peaks=peaks, window=window))
    # the paper's case on both kernels
    system = System.from_gap_ratio("cid", mu=0.01, beta=0.0048, e=0.25, gap_ratio=1.6)
    proto = Protocol(start="left")
    t_old, old = best_time(lambda: simulate(system, 1.0, proto), reps)
    scene = paper_scene("cid", 0.01, 0.0048, 0.25, system.gap, 1.0, start="left")
    general = scene_case("paper CID g = 1.6, left start, 500 periods (scene core)", scene, reps)
    # what the paper loop measures, the amplitude alone (no certified peaks): the like-for-like comparison
    alike = scene_case("paper CID g = 1.6, left start, 500 periods (scene core, amplitude alone)", scene, reps,
                       peaks=())
    paper = {"case": "paper CID g = 1.6, left start, 500 periods (specialised kernel)", "ms_per_run": 1e3 * t_old,
             "impacts": old.diagnostics["impacts"],
             "us_per_impact": 1e6 * t_old / old.diagnostics["impacts"],
             "scene_over_specialised": general["ms_per_run"] / (1e3 * t_old),
             "scene_amplitude_alone_over_specialised": alike["ms_per_run"] / (1e3 * t_old)}
    print(json.dumps(paper))
    cases += [general, alike, paper]
    bare = scenes["3 storeys, bare, El Centro 0.35 g, scene core"][0]
    peer = opensees_case("3 storeys, bare, El Centro 0.35 g, OpenSees linear Newmark at the record's step",
                         bare.building, bare.load)
    cases += [peer] if peer else []
    for size in ("1 storey", "3 storeys"):
        core, exact = (next(c for c in cases if c["case"].startswith(size) and c["case"].endswith(end))
                       for end in ("scene core", "exact propagator"))
        print(json.dumps({"case": f"{size}, bare: scene core over exact propagator",
                          "ratio": core["ms_per_run"] / exact["ms_per_run"]}))
    report = {"cases": cases, "machine": {"python": platform.python_version(), "processor": platform.processor(),
                                          "machine": platform.machine()}, "packages": package_versions()}
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(report, indent=1) + "\n")
    print(f"\n{'case':62s} {'ms/run':>9s} {'segments':>9s} {'impacts':>8s} {'us/seg':>8s}")
    for c in cases:
        print(f"{c['case'][:62]:62s} {c['ms_per_run']:9.2f} {c.get('segments', 0):9d} {c['impacts']:8d} "
              f"{c.get('us_per_segment', float('nan')):8.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
