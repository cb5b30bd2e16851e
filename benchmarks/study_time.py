"""Where a study's time went: job-seconds per stage, and the critical path through the rules.

Reads the benchmark file of every job (results/benchmarks/<rule>[/<job>].tsv, written by each rule's
`benchmark:`), groups the rules by the stage file that defines them (workflow/rules/<stage>.smk), and
walks the rule graph (`snakemake --rulegraph`) for the longest chain of rules, each weighted by its
longest job: no number of cores can finish the study faster than that chain.

    python benchmarks/study_time.py [--root .] [--results results] [--configfile config/config.yaml ...] [--json]
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path


def job_seconds(bench: Path) -> dict[str, list[float]]:
    """{rule: [seconds of each job]}, the mean of a job's repeats."""
    out: dict[str, list[float]] = defaultdict(list)
    for path in sorted(bench.rglob("*.tsv")):
        # benchmarks/<rule>.tsv, or benchmarks/<rule>/<wildcards...>.tsv (one folder level per wildcard)
        parts = path.relative_to(bench).parts
        rule = parts[0] if len(parts) > 1 else path.stem
        with open(path, newline="") as fh:
            values = [float(row["s"]) for row in csv.DictReader(fh, delimiter="\t") if row.get("s")]
        if values:
            out[rule].append(sum(values) / len(values))
    return dict(out)


def rule_stages(rules_dir: Path) -> dict[str, str]:
    """{rule: the stage file (without .smk) that defines it}."""
    stages = {}
    for smk in sorted(rules_dir.glob("*.smk")):
        for name in re.findall(r"^rule (\w+):", smk.read_text(), flags=re.MULTILINE):
            stages[name] = smk.stem
    return stages


def rule_graph(root: Path, configfiles: list[str] | None) -> dict[str, set[str]]:
    """{rule: the rules it needs}, from snakemake --rulegraph."""
    cmd = [sys.executable, "-m", "snakemake", "--rulegraph", "--quiet"]
    if configfiles:
        cmd += ["--configfile", *configfiles]
    dot = subprocess.run(cmd, cwd=root, capture_output=True, text=True, check=True).stdout
    names = dict(re.findall(r"^\s*(\d+)\[label = \"(\w+)\"", dot, flags=re.MULTILINE))
    needs: dict[str, set[str]] = {name: set() for name in names.values()}
    for src, dst in re.findall(r"^\s*(\d+) -> (\d+)", dot, flags=re.MULTILINE):
        needs[names[dst]].add(names[src])
    return needs


def critical_path(needs: dict[str, set[str]], weight: dict[str, float]) -> tuple[float, list[str]]:
    """The longest chain of rules by weight (rules without a benchmark weigh nothing)."""
    memo: dict[str, tuple[float, list[str]]] = {}

    def longest(rule: str) -> tuple[float, list[str]]:
        if rule not in memo:
            best = max((longest(dep) for dep in needs.get(rule, ())), default=(0.0, []))
            memo[rule] = (best[0] + weight.get(rule, 0.0), best[1] + [rule])
        return memo[rule]

    return max((longest(rule) for rule in needs), default=(0.0, []))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", default=".", help="the workflow's folder (the repository)")
    ap.add_argument("--results", default="results", help="the study's results folder, under the root")
    ap.add_argument("--configfile", nargs="+", default=None,
                    help="the configuration files the study ran with (make paper: config/config.yaml config/paper.yaml)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)
    root = Path(args.root)
    jobs = job_seconds(root / args.results / "benchmarks")
    if not jobs:
        print(f"no benchmark files under {args.results}/benchmarks: run the study first", file=sys.stderr)
        return 2
    stages = rule_stages(root / "workflow" / "rules")
    per_stage: dict[str, float] = defaultdict(float)
    for rule, secs in jobs.items():
        per_stage[stages.get(rule, "other")] += sum(secs)
    length, path = critical_path(rule_graph(root, args.configfile), {r: max(s) for r, s in jobs.items()})
    total = sum(per_stage.values())
    if args.json:
        print(json.dumps({"job_seconds_total": total, "job_seconds_per_stage": dict(per_stage),
                          "critical_path_seconds": length, "critical_path": path}, indent=1))
        return 0
    print(f"{'stage':14s} {'job-seconds':>12s} {'share':>7s}")
    for stage, secs in sorted(per_stage.items(), key=lambda kv: -kv[1]):
        print(f"{stage:14s} {secs:12.1f} {100 * secs / total:6.1f}%")
    print(f"{'total':14s} {total:12.1f}")
    print(f"critical path ({length:.1f} s, the least wall time on any number of cores): {' -> '.join(path)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
