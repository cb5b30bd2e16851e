"""Where a scene run's time goes, by the engine's compiled functions: Linux `perf` over repeated runs of one of
bench_scene.py's El Centro cases, with a perf map that names every function compiled into the scene loop.

numba loads a cached kernel as anonymous code, which perf shows as bare addresses.  The profiled process keeps
the object code numba hands LLVM as it loads the kernel, reads its function symbols (`readelf`), asks the loaded
kernel where each one lives, and writes /tmp/perf-<pid>.map, the file perf reads to name anonymous code.  A
function inlined into its caller (the loop's named steps, `inline="always"`) counts as its caller; the time of the
Python around a run (the scene's arrays, the result) shows as the interpreter's and the libraries'.

    python -m impact.kernels tools/engine_profile.py --case "3 storeys, CID at the roof" [--runs 1500] [--out F]

The case is matched as the start of a case's name in bench_scene.record_scenes().  Needs Linux perf (the
`linux-perf` package) and readelf (binutils); prints each function's share of the samples, highest first.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
READY = "ready"

_COMPONENT = re.compile(r"(\d+)")
_ESCAPES = {"_3c": "<", "_3e": ">"}  # numba's mangling of the characters of "<locals>"


def demangle(symbol: str) -> str:
    """A numba symbol's dotted name (_ZN6impact6engine10clear_step11clear_stepsB4v530...E... ->
    impact.engine.clear_step.clear_steps); any other symbol as it is."""
    if not symbol.startswith("_ZN"):
        return symbol
    parts, i = [], 3
    while i < len(symbol) and symbol[i].isdigit():
        length = _COMPONENT.match(symbol, i)
        i = length.end()
        parts.append(symbol[i: i + int(length.group(1))])
        i += int(length.group(1))
    name = ".".join(parts)
    for code, char in _ESCAPES.items():
        name = name.replace(code, char)
    return name or symbol


def function_symbols(object_code: bytes) -> list[str]:
    """The names of the functions an ELF object defines."""
    with tempfile.NamedTemporaryFile(suffix=".o") as fh:
        fh.write(object_code)
        fh.flush()
        table = subprocess.run(["readelf", "-sW", fh.name], capture_output=True, text=True, check=True).stdout
    names = []
    for line in table.splitlines():
        cols = line.split()
        if len(cols) >= 8 and cols[3] == "FUNC" and cols[6] != "UND":
            names.append(cols[7])
    return names


def perf_map(addresses: dict[int, str]) -> str:
    """perf's map of anonymous code: each function from its address to the next one's."""
    starts = sorted(addresses)
    ends = starts[1:] + [starts[-1] + 4096]
    return "".join(f"{a:x} {b - a:x} {demangle(addresses[a])}\n" for a, b in zip(starts, ends))


def _keep_object_code() -> dict:
    """Keeps the object code of every kernel numba loads from here on ({library name: bytes})."""
    from numba.core import codegen

    kept = {}
    original = codegen.CPUCodeLibrary._set_compiled_object

    def keep(library, object_code):
        kept[library.name] = object_code
        return original(library, object_code)

    codegen.CPUCodeLibrary._set_compiled_object = keep
    return kept


def _kernel_addresses(dispatcher, kept: dict) -> dict[int, str]:
    """{address: symbol} of every function compiled into each loaded specialisation of the dispatcher: a kernel
    loaded from numba's cache by its object code kept as it loaded, one compiled in this process by the object
    code numba keeps for its cache."""
    addresses = {}
    for result in dispatcher.overloads.values():
        library = result.library
        engine = library._codegen._engine
        object_code = kept.get(library.name) or library._compiled_object
        if object_code is None:
            raise SystemExit(f"no object code of {library.name} to read its functions from")
        for name in function_symbols(object_code):
            address = engine.get_function_address(name)
            if address:
                addresses[address] = name
    return addresses


def bench_case(case: str) -> tuple:
    """bench_scene's case whose name starts with `case`: (scene, peaks, window); an unknown one names the cases."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from bench_scene import record_scenes

    cases = record_scenes()
    named = [name for name in cases if name.startswith(case)]
    if not named:
        raise SystemExit(f"--case {case!r} starts no case's name: one of {', '.join(map(repr, cases))}")
    return cases[named[0]]


def profiled_process(case: str, runs: int) -> None:
    """The process perf samples: loads the case's kernel, writes its perf map, says READY, waits for a line on
    stdin, then runs the case `runs` times, prints the milliseconds per run and waits for a line again."""
    kept = _keep_object_code()
    from impact.engine.scene_loop import run_scene
    from impact.engine.scenes import simulate_scene

    scene, peaks, window = bench_case(case)
    simulate_scene(scene, peaks=peaks, window=window)
    Path(f"/tmp/perf-{os.getpid()}.map").write_text(perf_map(_kernel_addresses(run_scene, kept)))
    print(READY, flush=True)
    sys.stdin.readline()
    t0 = time.perf_counter()
    for _ in range(runs):
        simulate_scene(scene, peaks=peaks, window=window)
    print(json.dumps({"ms_per_run": 1e3 * (time.perf_counter() - t0) / runs}), flush=True)
    sys.stdin.readline()  # until perf has stopped: the interpreter's exit (a full collection of every object) is
    # not the runs' time, and it took a tenth of a short case's samples


def shares(report: str) -> Counter:
    """{function: percent of the samples} from `perf report --sort sym --stdio`."""
    out = Counter()
    for line in report.splitlines():
        cols = line.split(None, 2)
        if len(cols) == 3 and cols[0].endswith("%") and cols[1] in ("[.]", "[k]"):
            out[demangle(cols[2].strip())] += float(cols[0].rstrip("%"))
    return out


def profile(case: str, runs: int) -> dict:
    missing = [tool for tool in ("perf", "readelf") if shutil.which(tool) is None]
    if missing:
        raise SystemExit(f"{' and '.join(missing)} not found: install Linux perf (linux-perf) and binutils")
    child = subprocess.Popen([sys.executable, "-m", "impact.kernels", __file__, "--profiled", "--case", case,
                              "--runs", str(runs)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    if child.stdout.readline().strip() != READY:
        raise SystemExit("the profiled process did not start (see its error above)")
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / "perf.data"
        perf = subprocess.Popen(["perf", "record", "-q", "-F", "4999", "-p", str(child.pid), "-o", str(data)])
        time.sleep(0.5)  # perf attached
        child.stdin.write("go\n")
        child.stdin.flush()
        timing = json.loads(child.stdout.readline())
        perf.send_signal(signal.SIGINT)
        perf.wait()
        child.stdin.write("done\n")
        child.stdin.flush()
        child.wait()
        report = subprocess.run(["perf", "report", "-i", str(data), "--sort", "sym", "--stdio", "-q"],
                                capture_output=True, text=True, check=True).stdout
    Path(f"/tmp/perf-{child.pid}.map").unlink(missing_ok=True)
    return {"case": case, "runs": runs, **timing, "percent": dict(shares(report).most_common())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--case", default="3 storeys, CID at the roof", help="the start of a bench_scene case's name")
    ap.add_argument("--runs", type=int, default=1500)
    ap.add_argument("--out", help="write the shares here (JSON)")
    ap.add_argument("--profiled", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.profiled:
        profiled_process(args.case, args.runs)
        return 0
    bench_case(args.case)  # an unknown case is said here, not by the process perf would wait on
    result = profile(args.case, args.runs)
    print(f"{result['case']}: {result['ms_per_run']:.3f} ms per run over {args.runs} runs")
    for name, pct in list(result["percent"].items())[:30]:
        print(f"{pct:6.2f} %  {name}")
    if args.out:
        Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
