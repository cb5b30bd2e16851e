"""The scene engine on thousands of random scenes with a fresh seed: which promises break, how often, and how to
reproduce each break.

The scenes and the promises are the test suite's probe (``tests/probe.py``: uniform or uneven buildings, any gap
and restitution, friction, harmonic, recorded, Kanai-Tajimi and wind loads; finished, finite, energy balanced, no
unit through its wall beyond what its position is known to, no dense sample above a certified peak), drawn wider
(probe.WIDE: up to 10 storeys, 4 dampers of up to 12 units, where the suite's stop at 4, 3 and 6), and a share of
them on buildings that yield (probe.draw_yielding_scene: perfectly plastic or hardening storeys, with and without P-delta and a collapse limit).  The suite runs 300 fixed scenes in a minute; this script
runs as many as asked, in worker processes with a time bound per scene, with a new seed unless one is given, so
that it keeps finding what the fixed 300 cannot.

    python tools/probe_scenes.py --scenes 3000                 # fresh seed, 2 workers
    python tools/probe_scenes.py --scenes 3000 --seed 12345    # the same scenes again
    python tools/probe_scenes.py --reproduce 12345 17          # one scene, in this process
    python tools/probe_scenes.py --scenes 3000 --yielding 0    # elastic buildings only

It prints, per class of break, how many scenes broke it and the worst few (seed and index, which is the
reproducer: scene i of seed s is yielding if ``default_rng([s, i, 2]).random()`` is below the yielding share, and
is drawn from ``numpy.random.default_rng([s, i, 1])`` if so, else from ``default_rng([s, i])``, so that a seed's
elastic scenes are the ones it drew before yielding buildings existed), then its yielding scenes by their
post-yield stiffness nearest zero (bands of |b k - P/h| / k, with the energy breaks in each: near zero the exact
flow loses digits, docs/model.md), then the worst energy breaks run again under other OpenBLAS kernel sets (a break
whose residual changes sign or spreads as wide as itself when only the round-off changes is round-off, and says so)
and the unit that spent the event budget of the first runs it stopped (the stop names the element whose event the
budget ran out at), and writes them all to ``--out`` (JSON).  A scene that runs past ``--timeout`` seconds is a
break of its own ("over the time bound").
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import multiprocessing.connection
import os
import secrets
import subprocess
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

from impact import kernels

kernels.apply()  # the study's kernels, before numpy loads here and in the workers, which inherit them

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from probe import (  # noqa: E402 (the path above first)
    SAMPLES,
    YIELDING_SHARE,
    is_yielding,
    scene_of,
    smallest_tangent,
    violations,
)

from impact.engine.run import simulate  # noqa: E402
from impact.engine.scenes import compile_scene_loops  # noqa: E402


def run_one(seed: int, index: int, share: float) -> dict:
    """One scene's run: its breaks, its time, and what kind of scene it is."""
    yielding = is_yielding(seed, index, share)
    try:
        scene, scale = scene_of(seed, index, share)
    except Exception as exc:  # noqa: BLE001 (a drawn input the model refuses, by its checks)
        return {"seed": seed, "index": index, "seconds": 0.0, "storeys": None, "dampers": None, "load": None,
                "yielding": yielding, "broke": [f"refused as drawn, {type(exc).__name__}: {str(exc).splitlines()[0][:160]}"]}
    started = time.perf_counter()
    residual = None
    try:
        times = np.linspace(0.0, scene.t_end, SAMPLES)
        result = simulate(scene, measures=("amplitude", "impacts", "peaks", "samples"), times=times)
        broke = violations(scene, scale, result)
        residual = result.diagnostics["energy_residual"]
    except Exception as exc:  # noqa: BLE001 (a refusal or a crash is what the probe reports)
        broke = [f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"]
    return {"seed": seed, "index": index, "seconds": time.perf_counter() - started, "broke": broke,
            "storeys": scene.building.storeys, "dampers": [d.kind for d in scene.dampers],
            "load": type(scene.load).__name__, "yielding": yielding, "tangent": smallest_tangent(scene),
            "energy_residual": residual}


def broke(run: dict, kind: str) -> bool:
    """Whether a run broke a promise of this kind (its break's text starts with it: "energy", "event budget")."""
    return any(text.startswith(kind) for text in run["broke"])


#: the kernel sets an energy break is run again under (OpenBLAS's names; the study's own is kernels.PINS'): what
#: the residual does when only the round-off changes
OTHER_KERNELS = ("SandyBridge", "Prescott")


def under_kernels(seed: int, index: int, share: float, kernel_set: str, timeout: float = 600.0) -> float | None:
    """Scene `index`'s energy residual run again in a fresh process under another OpenBLAS kernel set (None if it
    does not finish there within `timeout` seconds)."""
    env = dict(os.environ, **{kernels.PINS["openblas"].override: kernel_set})
    command = [sys.executable, "-m", "impact.kernels", __file__, "--reproduce", str(seed), str(index),
               "--yielding", str(share)]
    try:
        done = subprocess.run(command, env=env, capture_output=True, text=True, check=False, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    text = done.stdout[done.stdout.find("\n{") + 1:] if done.returncode == 0 else ""
    return json.loads(text).get("energy_residual") if text.startswith("{") else None


def sensitivity(residuals: list[float | None]) -> str:
    """What an energy break's residuals under several kernel sets say: "round-off" where they change sign or
    spread over at least half the largest (the break is as large as its round-off sensitivity, and no value of it
    is sharper than that), "systematic" where they agree, "unknown" where a run did not finish."""
    if not residuals or any(r is None for r in residuals):
        return "unknown"
    largest = max(abs(r) for r in residuals)
    changes_sign = min(residuals) < 0.0 < max(residuals)
    return "round-off" if changes_sign or max(residuals) - min(residuals) >= 0.5 * largest else "systematic"


def energy_sensitivity(runs: list[dict], seed: int, share: float, worst: int = 10) -> list[dict]:
    """The worst energy breaks, each run again under OTHER_KERNELS: its residuals and their verdict (sensitivity)."""
    broken = [r for r in runs if r.get("energy_residual") is not None and broke(r, "energy")]
    broken.sort(key=lambda r: -abs(r["energy_residual"]))
    out = []
    for run in broken[:worst]:
        others = {name: under_kernels(seed, run["index"], share, name) for name in OTHER_KERNELS}
        residuals = [run["energy_residual"], *others.values()]
        out.append({"index": run["index"], "study_kernels": run["energy_residual"], **others,
                    "verdict": sensitivity(residuals)})
    return out


def budget_spender(seed: int, index: int, share: float, kept: int = 200_000) -> dict:
    """Which unit spent a run's event budget: the run again with its first `kept` impacts recorded, and the unit
    with the most of them (a budget stop names the element whose event the budget ran out at, which need not be
    the one whose events spent it)."""
    scene, _ = scene_of(seed, index, share)
    recorded = simulate(scene, measures=("impacts", "records"), record=kept).records["unit"].astype(int)
    unit, count = Counter(recorded.tolist()).most_common(1)[0]
    _, damper = scene.unit_list()[unit]
    return {"index": index, "unit": unit, "kind": damper.kind, "e": damper.e, "gap_m": damper.gap,
            "share_of_recorded_impacts": count / len(recorded)}


def budget_spenders(runs: list[dict], seed: int, share: float, first: int = 10) -> list[dict]:
    """budget_spender of the first `first` runs the event budget stopped."""
    stopped = [r["index"] for r in runs if broke(r, "event budget")]
    return [budget_spender(seed, index, share) for index in stopped[:first]]


#: the bands of `smallest_tangent` the report counts scenes and energy breaks in (0 exactly: a perfectly plastic
#: storey without P-delta)
TANGENT_BANDS = (0.0, 1e-4, 1e-3, 3e-3, 1e-2, 1e-1, np.inf)


def by_tangent(runs: list[dict]) -> list[dict]:
    """Yielding scenes that ran, per band of their smallest post-yield stiffness: how many, and how many broke the
    energy balance."""
    ran = [r for r in runs if r.get("tangent") is not None]
    bands = [{"band": "0", "test": lambda t: t == 0.0}]
    bands += [{"band": f"{'(' if lo == 0.0 else '['}{lo:g}, {hi:g})",
               "test": lambda t, lo=lo, hi=hi: lo <= t < hi and t > 0.0}
              for lo, hi in zip(TANGENT_BANDS[:-1], TANGENT_BANDS[1:])]
    return [{"band": b["band"], "scenes": sum(b["test"](r["tangent"]) for r in ran),
             "energy_breaks": sum(b["test"](r["tangent"]) and broke(r, "energy")
                                  for r in ran)} for b in bands]


def break_class(text: str) -> str:
    """The class of a break: its words before the first number (the number is how far)."""
    words = []
    for word in text.split():
        if any(ch.isdigit() for ch in word):
            break
        words.append(word)
    return " ".join(words) or text


def severity(text: str) -> float:
    """How far a break went, where it says (its last number), for ranking the worst."""
    for word in reversed(text.replace(",", " ").split()):
        try:
            return abs(float(word))
        except ValueError:
            continue
    return float("inf")


def _worker(seed: int, share: float, conn) -> None:
    """Runs the scenes the probe sends, one at a time, answering each on its own pipe."""
    for index in iter(conn.recv, None):
        conn.send(run_one(seed, index, share))


class _Worker:
    """One worker process with a pipe of its own: no lock is shared with another worker, so killing one that
    overran its time bound cannot leave the others waiting on a lock it held."""

    def __init__(self, ctx, seed: int, share: float):
        self.conn, theirs = ctx.Pipe()
        self.proc = ctx.Process(target=_worker, args=(seed, share, theirs), daemon=True)
        self.proc.start()
        self.index, self.since = None, 0.0

    def give(self, index: int) -> None:
        self.index, self.since = index, time.monotonic()
        self.conn.send(index)

    def stop(self) -> None:
        self.proc.kill()
        self.proc.join()


def probe(seed: int, share: float, scenes: int, workers: int, timeout: float) -> list[dict]:
    """Every scene's run, in worker processes; a scene still running after `timeout` seconds is recorded as such
    and its worker replaced (numba's compiled loop cannot be interrupted from inside)."""
    ctx = multiprocessing.get_context("spawn")
    todo = list(range(scenes - 1, -1, -1))
    pool = [_Worker(ctx, seed, share) for _ in range(workers)]
    done: list[dict] = []
    for worker in pool:
        worker.give(todo.pop())
    while len(done) < scenes:
        ready = multiprocessing.connection.wait([w.conn for w in pool if w.index is not None], timeout=1.0)
        for i, worker in enumerate(pool):
            lost = None
            if worker.conn in ready:
                try:
                    done.append(worker.conn.recv())
                    worker.index = None
                except EOFError:  # the worker died on this scene (a crash of the process itself)
                    lost = f"the worker process died (exit code {worker.proc.exitcode})"
            elif worker.index is not None and time.monotonic() - worker.since > timeout:
                lost = f"over the time bound of {timeout:g} s"
            if lost:
                done.append({"seed": seed, "index": worker.index, "seconds": time.monotonic() - worker.since,
                             "storeys": None, "dampers": None, "load": None,
                             "yielding": is_yielding(seed, worker.index, share), "broke": [lost]})
                worker.stop()
                pool[i] = worker = _Worker(ctx, seed, share)
            if worker.index is None and todo:
                worker.give(todo.pop())
    for worker in pool:
        worker.stop()
    return sorted(done, key=lambda r: r["index"])


def summary(runs: list[dict], worst: int = 5) -> dict:
    classes: dict = defaultdict(list)
    for run in runs:
        for text in run["broke"]:
            classes[break_class(text)].append((severity(text), run["index"], text, bool(run["yielding"])))
    return {name: {"scenes": len(hits), "per_thousand": 1000.0 * len(hits) / len(runs),
                   "yielding": sum(y for *_, y in hits),
                   "worst": [{"index": i, "break": text, "yielding": y}
                             for _, i, text, y in sorted(hits, reverse=True)[:worst]]}
            for name, hits in sorted(classes.items(), key=lambda kv: -len(kv[1]))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=3000, help="how many random scenes (default 3000)")
    ap.add_argument("--seed", type=int, default=None, help="the probe's seed (default: a fresh one, printed)")
    ap.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--timeout", type=float, default=30.0,
                    help="seconds one scene may run, on one core (default 30, issue 42's bound)")
    ap.add_argument("--yielding", type=float, default=YIELDING_SHARE,
                    help=f"share of the scenes on buildings that yield, 0 to 1 (default {YIELDING_SHARE})")
    ap.add_argument("--out", type=Path, default=Path("probe_scenes.json"), help="where the runs and classes go")
    ap.add_argument("--reproduce", nargs=2, type=int, metavar=("SEED", "INDEX"), help="run one scene and print it")
    args = ap.parse_args(argv)
    if not 0.0 <= args.yielding <= 1.0:
        ap.error(f"--yielding must be a share from 0 to 1, not {args.yielding}")
    if args.reproduce:
        seed, index = args.reproduce
        scene, scale = scene_of(seed, index, args.yielding)
        print(scene, f"\nmotion scale {scale:.3g} m")
        print(json.dumps(run_one(seed, index, args.yielding), indent=1))
        return 0
    seed = args.seed if args.seed is not None else secrets.randbits(32)
    # every loop compiled before any scene is timed: a worker killed at its time bound while compiling would
    # lose the compilation, and the next scene of that kind would start it again
    compile_scene_loops(yielding=(False, True) if args.yielding > 0 else (False,))
    started = time.perf_counter()
    runs = probe(seed, args.yielding, args.scenes, args.workers, args.timeout)
    classes = summary(runs)
    seconds = [r["seconds"] for r in runs]
    report = {"seed": seed, "yielding_share": args.yielding, "scenes": len(runs),
              "yielding_scenes": sum(bool(r["yielding"]) for r in runs), "wall_seconds": time.perf_counter() - started,
              "broken_scenes": sum(bool(r["broke"]) for r in runs), "classes": classes,
              "slowest": sorted(({"index": r["index"], "seconds": r["seconds"]} for r in runs),
                                key=lambda r: -r["seconds"])[:10],
              "median_seconds": float(np.median(seconds)), "by_tangent": by_tangent(runs),
              "energy_under_other_kernels": energy_sensitivity(runs, seed, args.yielding),
              "event_budget_spent_by": budget_spenders(runs, seed, args.yielding), "runs": runs}
    args.out.write_text(json.dumps(report, indent=1) + "\n")
    print(f"seed {seed}: {len(runs)} scenes ({report['yielding_scenes']} yielding), {report['broken_scenes']} broke "
          f"a promise ({report['wall_seconds']:.0f} s; reproduce one with --reproduce {seed} INDEX "
          f"--yielding {args.yielding})")
    for name, c in classes.items():
        print(f"  {c['scenes']:5d} ({c['per_thousand']:.1f} per thousand, {c['yielding']} yielding)  {name}")
        for w in c["worst"][:3]:
            print(f"          scene {w['index']}{' (yielding)' if w['yielding'] else ''}: {w['break']}")
    print("  yielding scenes by their smallest post-yield stiffness |b k - P/h| / k: scenes, energy breaks")
    for band in report["by_tangent"]:
        print(f"    {band['band']:>14s}: {band['scenes']:5d}, {band['energy_breaks']}")
    if report["energy_under_other_kernels"]:
        print(f"  the worst energy breaks under the study's kernels and {', '.join(OTHER_KERNELS)}:")
        for e in report["energy_under_other_kernels"]:
            values = ", ".join("n/a" if e[k] is None else f"{e[k]:.2e}" for k in ("study_kernels", *OTHER_KERNELS))
            print(f"          scene {e['index']}: {values}: {e['verdict']}")
    if report["event_budget_spent_by"]:
        print("  who spent the event budget (the first stops, the unit with the most recorded impacts):")
        for b in report["event_budget_spent_by"]:
            print(f"          scene {b['index']}: unit {b['unit']} ({b['kind']}, e = {b['e']:.2f}, gap {b['gap_m']:.1e} m), "
                  f"{b['share_of_recorded_impacts']:.0%} of the impacts")
    print(f"written to {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
