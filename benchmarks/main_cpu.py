"""Run a command (a Snakemake run) and report its wall time, the CPU time of its main process alone, and all CPU.

    python benchmarks/main_cpu.py [--out FILE.json] -- snakemake --cores 2 ...

The main process's own user and system time (not its jobs'): what the scheduler costs the machine.  Read from
the process's own counters (psutil: /proc/<pid>/stat utime and stime, which leave out its children) every half
second until it exits; the last reading is at most half a second before the end.  The whole tree's CPU (the
main process, its jobs and theirs: every process it waited for) is read once at the end from this process's
children's rusage, which, unlike Snakemake's benchmark files, misses nothing (they sample a job's CPU every
half second for its first 15 s, then every 30 s, and lose what it spent after the last sample).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time

import psutil


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=None, help="also write the figures to this JSON file")
    ap.add_argument("command", nargs=argparse.REMAINDER, help="the command, after --")
    args = ap.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    start = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.Popen(command)
    watched = psutil.Process(proc.pid)
    user = system = 0.0
    while proc.poll() is None:
        try:
            times = watched.cpu_times()
            user, system = times.user, times.system
        except psutil.NoSuchProcess:
            break
        time.sleep(0.5)
    returncode = proc.wait()
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    tree = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    out = {"command": " ".join(command), "returncode": returncode, "wall_s": round(time.perf_counter() - start, 1),
           "main_user_s": round(user, 1), "main_system_s": round(system, 1),
           "main_cpu_s": round(user + system, 1), "tree_cpu_s": round(tree, 1),
           "jobs_cpu_s": round(tree - user - system, 1)}
    print(json.dumps(out))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(out, fh, indent=1)
    return out["returncode"]


if __name__ == "__main__":
    sys.exit(main())
