"""Buildings that yield: what they cost on the exact engine, and the peer (OpenSees' Steel01) beside it.

Part 1, the engine (one process, minimum of repeats after a warm-up that compiles): the 3-storey building
(T1 = 1 s, zeta = 2 %) under El Centro at 0.35 g, bare and with a CID of 2 % of its mass at the roof, elastic
and with storeys that yield at a drift of YIELD_DRIFT_M (hardening 0.05).  Printed: ms per run, us per event
(impacts and yield and unloading events), and the yielding run's time over the elastic one's.

Part 1b, the collapse stage's run (collapse.runs.collapse_run): the same building with P-delta, storeys 3.5 m
high yielding at 2 cm (b = 0.05), a 10 % collapse drift ratio, El Centro at 0.5 g, bare and with a CID, a PID and
a TMD of 2 %, asked for what the stage reads (impacts and drifts: no window) against the same run asked for the
amplitude too (the window's square integrated, as every run was before run.has_window): the window's cost.

Part 1c, the collapse stage's hunt (collapse.runs.traced): on the study's 3-storey 1 s archetype (config/config.yaml's
collapse section) under HUNT_MOTIONS, a CID, a PID and a TMD of 2 % (the impact dampers' clearance at gap ratio 1)
traced to collapse from the bare archetype's bracket of each motion against the same traced from the hunt's first
level, one after the other: runs, seconds and whether the two brackets overlap.

Part 2, the peer: a one-storey building (T = 1 s, zeta = 5 %, yield drift 30 mm, perfectly plastic) under El
Centro at 0.5 g.  Ours is exact (b = 0); OpenSees has one zeroLength Steel01 (b = 1e-9, its nearest to
perfectly plastic) beside a viscous dashpot of the same damping, Newmark's average acceleration and Newton,
at the record's step and at fractions of it, until one run takes longer than the budget.  Printed per step:
OpenSees' wall time, its peak drift and plastic offset against ours, and the same for ours.

    make peer        # installs OpenSees (openseespy, with the system's BLAS and LAPACK) and runs both peers
    python -m impact.kernels benchmarks/bench_yield.py [--quick] [--budget-s 60] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from bench_scene import best_time

from impact.engine.run import simulate
from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.kinds import CID, PID, TMD
from impact.model.records import load_record
from impact.model.scene import Damper, GroundMotion, Scene
from impact.stages.collapse.plan import archetype
from impact.stages.collapse.runs import traced
from impact.stages.ida.runs import bare_runs, design_peak, designed_damper

YIELD_DRIFT_M, HARDENING = 0.01, 0.05
PEER = {"period_s": 1.0, "zeta": 0.05, "yield_drift_m": 0.03, "pga_g": 0.5, "floor_mass_kg": 1.0e5}
STEEL01_B = 1e-9  # OpenSees' Steel01 with b = 0 has a singular tangent after yield


def engine_case(name: str, scene: Scene, repeats: int) -> dict:
    seconds, res = best_time(lambda: simulate_scene(scene), repeats)
    d = res.diagnostics
    yields = int(res.storeys.yield_events.sum()) if res.storeys is not None else 0
    events = d["impacts"] + yields
    out = {"case": name, "ms_per_run": 1e3 * seconds, "segments": d["segments"], "clear_steps": d["clear_steps"],
           "impacts": d["impacts"], "yield_events": yields, "us_per_event": 1e6 * seconds / events if events else None,
           "peak_drift_m": float(np.max(res.peak_drifts)), "energy_residual": d["energy_residual"]}
    print(json.dumps(out))
    return out


def engine_cases(repeats: int) -> list[dict]:
    three = Building.uniform(3, 1.0, 0.02)
    yielding = three.yielding(YIELD_DRIFT_M, HARDENING)
    quake = GroundMotion.from_record(load_record("elcentro"), pga_g=0.35)
    cid = Damper("cid", 0.02 * three.total_mass, gap=0.05, e=0.5)
    cases = []
    for dampers, label in (((), "bare"), ((cid,), "CID at the roof")):
        elastic = engine_case(f"3 storeys, {label}, elastic", Scene(three, dampers, quake), repeats)
        yielded = engine_case(f"3 storeys, {label}, yielding (d_y = {YIELD_DRIFT_M} m, b = {HARDENING})",
                              Scene(yielding, dampers, quake), repeats)
        yielded["over_elastic"] = yielded["ms_per_run"] / elastic["ms_per_run"]
        print(json.dumps({"case": label, "yielding_over_elastic": yielded["over_elastic"]}))
        cases += [elastic, yielded]
    return cases


def collapse_run_cases(repeats: int) -> list[dict]:
    three = Building.uniform(3, 1.0, 0.02)
    archetype = three.yielding(0.02, HARDENING, storey_height=3.5, p_delta=True)
    quake = GroundMotion.from_record(load_record("elcentro"), pga_g=0.5)
    m = 0.02 * three.total_mass
    dampers = {"bare": (), "CID": (Damper("cid", m, gap=0.05, e=0.5),),
               "PID": (Damper("pid", m, gap=0.1, e=0.5, tuning=1.0),), "TMD": (Damper("tmd", m, tuning=0.98, damping=0.08),)}
    cases = []
    for label, ds in dampers.items():
        scene = Scene(archetype, ds, quake, collapse_drift_ratio=0.1)
        plain, res = best_time(lambda: simulate(scene, measures=("impacts", "drifts")), repeats)
        window, _ = best_time(lambda: simulate(scene, measures=("amplitude", "impacts", "drifts")), repeats)
        out = {"case": f"collapse run, {label}", "ms_per_run": 1e3 * plain, "ms_with_window": 1e3 * window,
               "over_with_window": plain / window, "peak_drift_m": float(np.max(res.peak_drifts)),
               "impacts": res.impacts}
        print(json.dumps(out))
        cases.append(out)
    return cases


#: far-field and near-field motions of FEMA P695's sets (both components of two records each)
HUNT_MOTIONS = ("fema-farfield:1:a", "fema-farfield:1:b", "fema-farfield:7:a", "fema-farfield:7:b",
                "fema-nearfield:2:a", "fema-nearfield:2:b", "fema-nearfield:9:a", "fema-nearfield:9:b")


def collapse_hunt_cases(building_name: str = "s3_T1") -> list[dict]:
    study = yaml.safe_load((Path(__file__).resolve().parents[1] / "config" / "config.yaml").read_text())
    cfg, loads = study["collapse"], study["loads"]
    ida = {**study["ida"], "motions": list(HUNT_MOTIONS)}
    building = archetype(cfg, ida, loads, building_name)
    ida_bare = bare_runs(ida, loads, building_name)
    bare = traced(cfg, building, (), ida_bare)
    peak = design_peak(ida_bare, ida["design_sa_g"])
    cases = []
    for kind in (CID, PID, TMD):
        dampers = (designed_damper(loads, ida, building, kind, 0.02, {0.02: 1.0}, peak),)
        traced(cfg, building, dampers, ida_bare.isel(motion=[0]))  # compiles the kind's loop, outside the timing
        start = time.perf_counter()
        from_bare = traced(cfg, building, dampers, ida_bare, bare)
        middle = time.perf_counter()
        hunted = traced(cfg, building, dampers, ida_bare)
        end = time.perf_counter()
        out = {"case": f"collapse hunt, {building_name}, {kind} of 2 %", "motions": len(HUNT_MOTIONS),
               "runs_from_bare": int(from_bare["runs"].sum()), "runs_hunted": int(hunted["runs"].sum()),
               "s_from_bare": middle - start, "s_hunted": end - middle, "time_ratio": (middle - start) / (end - middle),
               "brackets_overlap": bool((from_bare["standing_sa"] < hunted["collapse_sa"]).all()
                                        and (hunted["standing_sa"] < from_bare["collapse_sa"]).all())}
        print(json.dumps(out))
        cases.append(out)
    return cases


def peer_scene() -> Scene:
    b = Building.uniform(1, PEER["period_s"], PEER["zeta"], floor_mass=PEER["floor_mass_kg"])
    return Scene(b.yielding(PEER["yield_drift_m"], 0.0),
                 (), GroundMotion.from_record(load_record("elcentro"), pga_g=PEER["pga_g"]))


def opensees_run(scene: Scene, dt: float) -> dict:
    """The one-storey building in OpenSees: Steel01 and a viscous dashpot in parallel, Newmark, Newton."""
    import openseespy.opensees as ops

    b = scene.building
    m, k, c = b.masses[0], b.storey_stiffness[0], b.damping[0, 0]
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(1, 0.0)
    ops.node(2, 0.0, "-mass", m)
    ops.fix(1, 1)
    ops.uniaxialMaterial("Steel01", 1, k * PEER["yield_drift_m"], k, STEEL01_B)
    ops.uniaxialMaterial("Viscous", 2, c, 1.0)
    ops.element("zeroLength", 1, 1, 2, "-mat", 1, 2, "-dir", 1, 1)
    load = scene.load
    ops.timeSeries("Path", 1, "-dt", load.dt, "-values", *load.accel.tolist())  # it applies -m a_g, as ours
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("FullGeneral")
    ops.test("NormDispIncr", 1e-12, 50)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    steps = int(round(scene.t_end / dt))
    with tempfile.TemporaryDirectory() as folder:
        # the peak from OpenSees' own envelope, every step in one call: a step driven from Python cost it 1.36 times
        # its time at the finest step (measured 2026-11-30)
        envelope = Path(folder) / "envelope.out"
        ops.recorder("EnvelopeNode", "-file", str(envelope), "-precision", 17, "-node", 2, "-dof", 1, "disp")
        t0 = time.perf_counter()
        status = ops.analyze(steps, dt)
        seconds = time.perf_counter() - t0
        # the plastic offset at the end: the drift less the elastic part of Steel01's stress
        offset = ops.nodeDisp(2, 1) - ops.eleResponse(1, "material", 1, "stress")[0] / k
        ops.wipe()  # closes the recorder, which writes the envelope: its rows are min, max and max |u|
        peak = float(np.loadtxt(envelope)[-1])
    return {"dt_s": dt, "seconds": seconds, "peak_drift_m": peak, "plastic_offset_m": offset, "converged": status == 0}


def peer_cases(repeats: int, budget_s: float) -> dict:
    scene = peer_scene()
    # asked for what is compared, the storey's certified peak drift, as OpenSees records its drift's envelope alone
    seconds, ours = best_time(lambda: simulate(scene, measures=("drifts",)), repeats)
    exact = {"seconds": seconds, "peak_drift_m": float(ours.storeys.peak_drifts[0]),
             "plastic_offset_m": float(ours.storeys.plastic_offsets[0]),
             "yield_events": int(ours.storeys.yield_events.sum())}
    print(json.dumps({"ours": exact}))
    ladder = []
    for divisor in (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000):
        run = opensees_run(scene, scene.load.dt / divisor)
        run["peak_error"] = abs(run["peak_drift_m"] / exact["peak_drift_m"] - 1.0)
        run["offset_error_over_dy"] = abs(run["plastic_offset_m"] - exact["plastic_offset_m"]) / PEER["yield_drift_m"]
        run["over_ours"] = run["seconds"] / seconds
        print(json.dumps(run))
        ladder.append(run)
        if run["seconds"] > budget_s or run["peak_error"] <= 1e-6:
            break
    return {"ours": exact, "opensees": ladder}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats (numbers are noisier)")
    ap.add_argument("--budget-s", type=float, default=60.0, help="stop the peer's ladder after a run this long")
    ap.add_argument("--no-peer", action="store_true", help="the engine's part only (no OpenSees)")
    ap.add_argument("--out", default="benchmarks/results/yield.json")
    args = ap.parse_args(argv)
    reps = 2 if args.quick else 7
    out = {"engine": engine_cases(reps), "collapse_run": collapse_run_cases(reps), "collapse_hunt": collapse_hunt_cases()}
    if not args.no_peer:
        out["peer"] = peer_cases(reps, args.budget_s)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
