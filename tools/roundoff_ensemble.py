"""The smoke study under several kernel sets: how far round-off alone moves each number of its fingerprint.

Each member of the ensemble runs the whole smoke study (``config/smoke.yaml``) in a copy of the workflow, with
OpenBLAS held to another kernel set or numpy's own vector loops left to the CPU (the overrides of
:mod:`impact.kernels`): the rounding another machine would do.  The spread of each fingerprint entry
(``tests/reference.smoke_digest``) over the members is its measured round-off sensitivity; the fingerprint test
holds the study to it (``tests/test_pipeline.py``), never to one tolerance for all.

    python tools/roundoff_ensemble.py                 # every member; prints each one's entries beyond 1e-9
    python tools/roundoff_ensemble.py --write         # and writes tests/data/smoke_reference.json
    python tools/roundoff_ensemble.py --members skylakex generic   # some members only (check, no write)

``--write`` takes the fingerprint from the pinned member (the study's own kernel set) and the spread from all,
so regenerate only when a change is meant to move numbers, or for a new constraints.txt.  About 90 s a member
on 2 cores once the kernels are compiled (``make setup``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from reference import FINGERPRINT_FLOOR as FLOOR  # noqa: E402
from reference import copy_workflow, smoke_digest  # noqa: E402
from study_time import job_seconds, rule_stages  # noqa: E402

from impact import kernels  # noqa: E402 (the paths above first)

REFERENCE = ROOT / "tests" / "data" / "smoke_reference.json"
#: the pinned member, whose numbers the fingerprint holds
PINNED = "pinned"
OPENBLAS, NUMPY = kernels.PINS["openblas"].override, kernels.PINS["numpy"].override
#: name: (the overrides of impact.kernels for the study's processes, the CPU features it needs)
MEMBERS = {
    PINNED: ({}, ()),
    "skylakex": ({OPENBLAS: "SkylakeX"}, ("avx512f",)),
    "sandybridge": ({OPENBLAS: "Sandybridge"}, ("avx",)),
    "generic": ({OPENBLAS: "Prescott"}, ()),
    "numpy-avx512": ({NUMPY: kernels.NATIVE}, ("avx512f",)),
}


def runnable(name: str) -> bool:
    return set(MEMBERS[name][1]) <= (kernels.cpu_flags() or set())


def member_environment(name: str) -> dict:
    overrides = {pin.override for pin in kernels.PINS.values()}
    return {k: v for k, v in os.environ.items() if k not in overrides} | MEMBERS[name][0]


def run_member(name: str, scratch: Path) -> tuple[dict, dict]:
    """The smoke study's fingerprint with one member's kernels, and its job-seconds per stage."""
    work = copy_workflow(ROOT, scratch / name)
    cmd = [sys.executable, "-m", "snakemake", "--cores", "2", "--configfile", "config/smoke.yaml", "--quiet"]
    proc = subprocess.run(cmd, cwd=work, env=member_environment(name), capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"member {name}: the smoke study failed\n{proc.stderr[-3000:]}")
    return smoke_digest(work / "results"), stage_seconds(work)


def stage_seconds(work: Path) -> dict:
    """Job-seconds per stage of a finished study (what this member's kernels cost)."""
    stages = rule_stages(work / "workflow" / "rules")
    out: dict = {}
    for rule, seconds in job_seconds(work / "results" / "benchmarks").items():
        stage = stages.get(rule, rule)
        out[stage] = out.get(stage, 0.0) + sum(seconds)
    return out


def _scale(value: float) -> float:
    return max(abs(value), 1e-3)


def spreads(digests: dict) -> dict:
    """Per fingerprint entry, the largest minus the smallest of each of its four figures (count, sum, sum of
    squares, NaNs) over the members."""
    keys = set.intersection(*(set(d) for d in digests.values()))
    out = {}
    for key in sorted(keys):
        rows = [d[key] for d in digests.values()]
        out[key] = [max(r[i] for r in rows) - min(r[i] for r in rows) for i in range(4)]
    return out


def beyond_floor(pinned: dict, other: dict) -> list:
    """(entry, relative move) of the entries a member moves beyond FLOOR of the pinned member's value."""
    moved = []
    for key, row in pinned.items():
        if key not in other:
            moved.append((key, float("inf")))
            continue
        rel = max(abs(other[key][i] - row[i]) / _scale(row[i]) for i in (1, 2))
        if rel > FLOOR or other[key][0] != row[0] or other[key][3] != row[3]:
            moved.append((key, rel))
    return moved


def reference(digests: dict) -> dict:
    """The fingerprint file: the pinned member's entries, each with its spread over the ensemble."""
    spread = spreads(digests)
    return {"members": sorted(digests),
            "entries": {key: {"stats": row, "spread": spread[key]} for key, row in digests[PINNED].items()}}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--members", nargs="+", choices=sorted(MEMBERS), default=sorted(MEMBERS))
    parser.add_argument("--write", action="store_true", help=f"write {REFERENCE.relative_to(ROOT)} (every member)")
    parser.add_argument("--digests", type=Path, help="also write every member's fingerprint to this JSON file")
    args = parser.parse_args(argv)
    members = [m for m in args.members if runnable(m)]
    if args.write and (set(members) != set(MEMBERS) or PINNED not in members):
        parser.error(f"--write needs every member, and this CPU runs only {', '.join(members)}")
    digests = {}
    with tempfile.TemporaryDirectory(prefix="roundoff-") as scratch:
        for name in [PINNED, *(m for m in members if m != PINNED)]:
            digests[name], seconds = run_member(name, Path(scratch))
            total = sum(seconds.values())
            split = ", ".join(f"{stage} {s:.0f}" for stage, s in sorted(seconds.items(), key=lambda kv: -kv[1]))
            print(f"{name}: {len(digests[name])} entries; {total:.0f} job-seconds ({split})", flush=True)
    if args.digests:
        args.digests.write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")
    for name, digest in digests.items():
        moved = beyond_floor(digests[PINNED], digest)
        folders = sorted({key.split("/")[0] for key, _ in moved})
        by_folder = ", ".join(f"{f} {sum(k.split('/')[0] == f for k, _ in moved)}" for f in folders)
        print(f"{name}: {len(moved)} entries beyond {FLOOR:g} of the pinned kernels ({by_folder or 'none'})")
        for key, rel in sorted(moved, key=lambda kv: -kv[1])[:20]:
            print(f"  {rel:9.2e}  {key}")
    if args.write:
        REFERENCE.write_text(json.dumps(reference(digests), indent=1, sort_keys=True) + "\n")
        print(f"wrote {REFERENCE.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
