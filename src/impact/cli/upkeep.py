"""The study's upkeep from the command line: impact compile (every kernel into numba's cache, once) and impact
verify-archive (a study archive against its manifest)."""

from __future__ import annotations

import concurrent.futures
import multiprocessing
import os
import sys
import time

# the engine's name for its cache folder is private; making it public would edit a module every rule imports,
# which reruns the whole study (code_deps)
from impact.engine.jitcache import _cache_dir as cache_dir
from impact.engine.paper import ensure_compiled, ensure_sampler_compiled
from impact.engine.scenes import simulate_scene, warm_up_scenes
from impact.model.kinds import KINDS, kinds_with
from impact.model.params import ParameterError
from impact.outputs.archive import archive_summary, check_archive
from impact.rig.simulator import warm_up


def verify_archive(args) -> dict:
    """Re-check an archive against its manifest: exit 1 naming each differing entry on stderr."""
    if not os.path.isfile(args.file):
        raise ParameterError(f"{args.file}: no such archive (give results/archive/impact-study-<commit>.tar.gz)")
    problems = check_archive(args.file)
    for path, reason in problems:
        print(f"{path}: {reason}", file=sys.stderr)
    if problems:
        raise SystemExit(1)
    return archive_summary(args.file)


def compile_kernels(args) -> dict:
    """Compile every kernel the study runs into numba's on-disk cache, once (make setup runs it): each
    specialisation of the scene loop the study runs (scenes.warm_up_scenes), the paper loop for each damper and
    its dense output, the virtual test rig.  One process a core compiles them side by side, the longest first
    (the scene loops); each kernel's compile lock keeps two from compiling one kernel."""
    start = time.perf_counter()
    tasks = [(simulate_scene, (scene,)) for scene in warm_up_scenes()]
    tasks += [(ensure_compiled, (kind, friction)) for kind in kinds_with("paper")
              for friction in ((False, True) if KINDS[kind].slides else (False,))]
    tasks += [(ensure_sampler_compiled, ()), (warm_up, ())]
    # spawned, not forked: each worker starts its own numba and LLVM, which a fork would share half-made
    with concurrent.futures.ProcessPoolExecutor(args.cores, mp_context=multiprocessing.get_context("spawn")) as pool:
        list(pool.map(_compile_one, tasks))  # in full: a worker's error is raised here
    return {"compiled": "every kernel of the study", "cache": os.fspath(cache_dir()), "processes": args.cores,
            "seconds": round(time.perf_counter() - start, 1)}


def _compile_one(task) -> None:
    """Run one warm-up call in a worker (a top-level function, so that the pool can send it)."""
    function, arguments = task
    function(*arguments)
