"""The study on a real SLURM scheduler gives exactly what it gives on this machine.

A single-node SLURM cluster is started with ../shared/tools/start-slurm.sh (root only: it
apt-installs slurmctld, slurmd and munge, and starts them without accounting). The smoke study
then runs twice, each in its own copy of the workflow: once through the SLURM executor, as users
run it (`snakemake --profile profiles/slurm`, plus options that make a test fast), and once on
this machine (`--cores 2`). The two must give identical datasets (apart from their creation
time), the same table and every figure. Both load the kernels the checkout compiled, but for the
paper loop's, which the SLURM run's sweep jobs compile into a cache of their own, side by side
under the compile lock. The wall time of each run is printed and written to a JSON file under
the test's temporary folder.

Without root, without the script, or when the script cannot bring the cluster up (no package
access, say), the SLURM tests are skipped with the reason; IMPACT_REQUIRE_SLURM=1 turns these
skips into failures (for CI machines that must run them). A cluster that is already answering is
used as it is and left running (on a real cluster, give pytest a --basetemp on storage the compute
nodes share); one this module started is stopped at the end.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import pytest
import xarray as xr
import yaml
from reference import HANG_GUARD_S, copy_workflow

pytestmark = pytest.mark.long_file(minutes=20)  # started first, the longest first (conftest)

ROOT = Path(__file__).resolve().parents[1]
# CI runs in a fresh clone with shared/ beside the repository
START_SLURM = ROOT.parent / "shared" / "tools" / "start-slurm.sh"
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
SMOKE = "config/smoke.yaml"
# the node advertises 4 CPUs (on a 2-CPU machine) so that single-thread jobs run side by side
NODE_CPUS = "4"
# dataset attributes that name the moment of the run rather than its content
RUN_SPECIFIC_ATTRS = {"date_created", "history"}


def _unavailable(reason: str):
    if os.environ.get("IMPACT_REQUIRE_SLURM") == "1":
        pytest.fail(f"IMPACT_REQUIRE_SLURM=1 but {reason}")
    pytest.skip(reason)


def _quiet(*cmd: str, timeout: float = 30) -> subprocess.CompletedProcess | None:
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except (OSError, subprocess.TimeoutExpired):
        return None


def _cluster_answers() -> bool:
    if not (shutil.which("scontrol") and shutil.which("sinfo")):
        return False
    ping = _quiet("scontrol", "ping")
    if ping is None or "is UP" not in ping.stdout:
        return False
    states = _quiet("sinfo", "-h", "-o", "%T")
    return states is not None and any(s.rstrip("*~#") in ("idle", "mixed", "allocated")
                                      for s in states.stdout.split())


def _sacct_works() -> bool:
    probe = _quiet("sacct", "-n", "-X")
    return probe is not None and probe.returncode == 0


@dataclass
class Cluster:
    started_here: bool
    status_command: str
    start_seconds: float | None


@pytest.fixture(scope="module")
def slurm_cluster():
    if _cluster_answers():
        # somebody's cluster: use it as it is (restarting it with our settings could
        # disturb their jobs) and leave it running
        yield Cluster(False, "sacct" if _sacct_works() else "squeue", None)
        return
    if os.geteuid() != 0:
        _unavailable("no SLURM cluster answering, and start-slurm.sh must run as root to start one; not root")
    if not START_SLURM.is_file():
        _unavailable(f"no SLURM cluster answering and no {START_SLURM}")
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(["bash", str(START_SLURM), "--no-accounting"], capture_output=True, text=True,
                              timeout=1200, env={**os.environ, "SLURM_NODE_CPUS": NODE_CPUS})
    except subprocess.TimeoutExpired as exc:
        subprocess.run(["bash", str(START_SLURM), "stop"], capture_output=True, timeout=300)
        _unavailable(f"start-slurm.sh did not bring the cluster up within {exc.timeout:.0f} s")
    start_seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-8:])
        subprocess.run(["bash", str(START_SLURM), "stop"], capture_output=True, timeout=300)
        _unavailable(f"start-slurm.sh could not bring the cluster up (exit {proc.returncode}):\n{tail}")
    try:
        # without accounting `sacct` fails and the plugin would wait for ever: poll with
        # squeue (the script keeps finished jobs visible for an hour, MinJobAge=3600)
        yield Cluster(True, "squeue", start_seconds)
    finally:
        stop = subprocess.run(["bash", str(START_SLURM), "stop"], capture_output=True, text=True, timeout=300)
        print(f"\n[slurm] start-slurm.sh stop: exit {stop.returncode}")


def _copy_workflow(dest: Path) -> Path:
    return copy_workflow(ROOT, dest)


def _env(work: Path, numba_cache: Path | None) -> dict:
    """Each run imports `impact` from its own copy (not from the checkout, which may change while
    the test runs). The SLURM run keeps its kernels in a numba cache of its own (NUMBA_CACHE_DIR;
    sbatch passes the environment on, --export=ALL); the local run (numba_cache None) keeps them
    beside its sources."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(work / "src"), *filter(None, [env.get("PYTHONPATH")])])
    env.pop("NUMBA_CACHE_DIR", None)
    if numba_cache is not None:
        env["NUMBA_CACHE_DIR"] = str(numba_cache)
    return env


# the kernels the SLURM run's sweep jobs compile themselves, side by side under the compile lock: the paper loop
# and its dense output (a minute or so; their files in numba's cache, and the stamps compile_lock leaves for them).
# Every other kernel each run loads, compiled by the checkout: compiling the scene loop's specialisations again
# would cost each run as long as make setup's compile, and test nothing more
SLURM_KERNELS = ("paper_loop.", "sampler.")
SLURM_COMPILES = (*SLURM_KERNELS, "compiled-paper-")

_CACHE_FOLDERS = """
import json
from impact.engine.scene_loop import run_scene
from impact.rig.simulator import _rig_run
print(json.dumps({f.py_func.__module__.rsplit(".", 1)[0]: f._cache._cache_path for f in (run_scene, _rig_run)}))
"""


def _with_compiled_kernels(work: Path, env: dict, leave_out: tuple[str, ...] = ()) -> None:
    """The checkout's compiled kernels where the copy `work`, run with `env`, looks for them, but for the files
    named `leave_out`. numba knows a source file by its size and modification time, which the copy keeps
    (shutil.copy2); the engine's stamps go with them, so that no job takes them for stale."""
    from impact.engine import jitcache, scene_loop
    from impact.rig import simulator

    out = subprocess.run([sys.executable, "-c", _CACHE_FOLDERS], env=env, capture_output=True, text=True,
                         check=True, timeout=HANG_GUARD_S)
    theirs = json.loads(out.stdout)
    ours = {f.py_func.__module__.rsplit(".", 1)[0]: Path(f._cache._cache_path)
            for f in (scene_loop.run_scene, simulator._rig_run)}
    for package, source in ours.items():
        _copy_files(source, Path(theirs[package]), lambda name: name.endswith((".nbi", ".nbc", ".stamp")), leave_out)
    # the lock's folder, where each compiled set leaves its stamp (jitcache.compile_lock)
    lock_folder = Path(env.get("NUMBA_CACHE_DIR") or theirs["impact.engine"])
    _copy_files(jitcache._cache_dir(), lock_folder, lambda name: name.startswith("compiled-"), leave_out)


def _copy_files(source: Path, dest: Path, wanted, leave_out: tuple[str, ...]) -> None:
    dest.mkdir(parents=True, exist_ok=True)
    for path in source.iterdir():
        if wanted(path.name) and not path.name.startswith(leave_out):
            shutil.copy2(path, dest / path.name)


def _snakemake(work: Path, env: dict, *args: str) -> tuple[float, str, str]:
    """Run Snakemake in `work`; return (wall seconds, stdout, stderr). On a timeout, interrupt it
    so that it cancels its own SLURM jobs."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([*SNAKEMAKE, *args], cwd=work, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        out, err = proc.communicate(timeout=HANG_GUARD_S)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGINT)
        try:
            out, err = proc.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            proc.kill()
            out, err = proc.communicate()
        raise AssertionError(f"snakemake {' '.join(args)} did not finish in {HANG_GUARD_S} s:\n{err[-4000:]}")
    seconds = time.perf_counter() - t0
    (work / "snakemake.stdout.txt").write_text(out)
    (work / "snakemake.stderr.txt").write_text(err)
    if proc.returncode != 0:
        logs = "\n".join(str(p) for p in sorted((work / ".snakemake").rglob("slurm_logs/**/*.log")))
        raise AssertionError(f"snakemake {' '.join(args)} failed (exit {proc.returncode}) in {work}:\n"
                             f"{out[-2000:]}\n{err[-5000:]}\nSLURM logs:\n{logs}")
    return seconds, out, err


@dataclass
class Runs:
    slurm: Path
    local: Path
    slurm_log: str
    numba_slurm: Path
    cluster: Cluster
    times: dict


@pytest.fixture(scope="module")
def runs(slurm_cluster, tmp_path_factory) -> Runs:
    base = tmp_path_factory.mktemp("slurm_vs_local")
    slurm, local = _copy_workflow(base / "slurm"), _copy_workflow(base / "local")
    numba_slurm = base / "numba-cache-slurm"
    slurm_env, local_env = _env(slurm, numba_slurm), _env(local, None)
    _with_compiled_kernels(slurm, slurm_env, leave_out=SLURM_COMPILES)
    _with_compiled_kernels(local, local_env)

    # what users type, plus: poll early, poll with squeue when there is no accounting, and
    # keep every job's SLURM log for the checks below (--configfile last: it takes every word)
    slurm_s, _, slurm_log = _snakemake(
        slurm, slurm_env,
        "--profile", "profiles/slurm",
        "--slurm-init-seconds-before-status-checks", "5",
        "--slurm-status-command", slurm_cluster.status_command,
        "--slurm-keep-successful-logs",
        "--configfile", SMOKE)
    local_s, _, _ = _snakemake(local, local_env, "--cores", "2", "--configfile", SMOKE)

    times = {
        "slurm_run_seconds": round(slurm_s, 1),
        "local_run_seconds": round(local_s, 1),
        "cluster_start_seconds": (None if slurm_cluster.start_seconds is None
                                  else round(slurm_cluster.start_seconds, 1)),
        "slurm_jobs": len(_submissions(slurm_log)),
        "slurm_status_command": slurm_cluster.status_command,
        "slurm_node_cpus": _node_cpus(),
        "local_cores": 2,
        "machine_cpus": os.cpu_count(),
        "numba_cache": "the checkout's kernels, but for the SLURM run's paper loop and dense output",
        "config": SMOKE,
    }
    path = base / "wall_times.json"
    path.write_text(json.dumps(times, indent=2) + "\n")
    print(f"\n[slurm] smoke study through SLURM: {slurm_s:.1f} s wall ({times['slurm_jobs']} SLURM jobs, "
          f"status via {slurm_cluster.status_command})")
    print(f"[slurm] smoke study on this machine (--cores 2): {local_s:.1f} s wall")
    if slurm_cluster.start_seconds is not None:
        print(f"[slurm] cluster start (not in the SLURM time): {slurm_cluster.start_seconds:.1f} s")
    print(f"[slurm] wall times written to {path}")
    return Runs(slurm, local, slurm_log, numba_slurm, slurm_cluster, times)


def _node_cpus() -> int | None:
    out = _quiet("sinfo", "-h", "-o", "%c")
    try:
        return int(out.stdout.split()[0].rstrip("+"))
    except (AttributeError, IndexError, ValueError):
        return None


def _submissions(log: str) -> dict[int, int]:
    """Snakemake job id -> SLURM job id, from the plugin's submission messages."""
    return {int(job): int(slurm) for job, slurm in
            re.findall(r"Job (\d+) has been submitted with SLURM jobid (\d+)", log)}


def _planned_jobs(log: str) -> dict[int, dict]:
    """Snakemake job id -> {'rule', 'resources'} from the job blocks Snakemake prints."""
    jobs = {}
    for block in re.split(r"\n(?=(?:local)?rule \w+:)", log):
        head = re.match(r"(?:local)?rule (\w+):", block)
        jobid = re.search(r"^\s+jobid: (\d+)$", block, re.M)
        res = re.search(r"^\s+resources: (.*)$", block, re.M)
        if head and jobid:
            resources = dict(item.split("=", 1) for item in res.group(1).split(", ")) if res else {}
            jobs[int(jobid.group(1))] = {"rule": head.group(1), "resources": resources}
    return jobs


def _job_stats(log: str) -> dict[str, int]:
    start = log.index("Job stats:")
    table = log[start:log.index("\n\n", start)] if "\n\n" in log[start:] else log[start:]
    return {line.split()[0]: int(line.split()[1]) for line in table.splitlines()
            if len(line.split()) == 2 and line.split()[1].isdigit()}


def _scontrol_job(slurm_id: int) -> dict[str, str]:
    out = _quiet("scontrol", "show", "job", "-o", str(slurm_id))
    if out is None or out.returncode != 0:
        return {}
    return dict(re.findall(r"(\w+)=(\S*)", out.stdout))


def _minutes(limit: str) -> float:
    days, _, clock = limit.rpartition("-")
    parts = [int(p) for p in clock.split(":")]
    while len(parts) < 3:
        parts.insert(0, 0)
    return int(days or 0) * 1440 + parts[0] * 60 + parts[1] + parts[2] / 60


def _slurm_records(runs: Runs) -> dict[int, tuple[dict, dict[str, str]]]:
    planned = _planned_jobs(runs.slurm_log)
    records = {}
    for job, slurm_id in _submissions(runs.slurm_log).items():
        info = _scontrol_job(slurm_id)
        if not info:
            if runs.cluster.started_here:
                raise AssertionError(f"scontrol knows no SLURM job {slurm_id} (MinJobAge is 3600 s here)")
            pytest.skip("the cluster already running forgets finished jobs (MinJobAge); cannot inspect them")
        records[slurm_id] = (planned[job], info)
    return records


# ------------------------------------------------------------------------------- tests


def test_slurm_profile_keys_are_not_shadowed_by_the_default_profile():
    """Snakemake reads profiles/default in every run, on top of --profile, key by key: a key
    in both would silently take the default profile's value in a SLURM run."""
    slurm = yaml.safe_load((ROOT / "profiles" / "slurm" / "config.yaml").read_text())
    default = yaml.safe_load((ROOT / "profiles" / "default" / "config.yaml").read_text()) or {}
    assert slurm["executor"] == "slurm"
    assert {"runtime", "mem_mb", "cpus_per_task"} <= set(slurm["default-resources"])
    shadowed = sorted(set(slurm) & set(default))
    assert not shadowed, (f"profiles/default sets {shadowed} too, and wins: remove them from one "
                          "of the two profiles")


@pytest.mark.slow
def test_slurm_run_gives_the_local_results(runs):
    names = sorted(p.name for p in (runs.local / "results" / "sweeps").glob("*.nc"))
    assert names, "the local run wrote no dataset"
    assert sorted(p.name for p in (runs.slurm / "results" / "sweeps").glob("*.nc")) == names
    for name in names:
        with xr.open_dataset(runs.slurm / "results" / "sweeps" / name) as a, \
                xr.open_dataset(runs.local / "results" / "sweeps" / name) as b:
            a, b = a.load(), b.load()
        for key in RUN_SPECIFIC_ATTRS:
            assert key in a.attrs and key in b.attrs, (name, key)
        a.attrs = {k: v for k, v in a.attrs.items() if k not in RUN_SPECIFIC_ATTRS}
        b.attrs = {k: v for k, v in b.attrs.items() if k not in RUN_SPECIFIC_ATTRS}
        # data variables, coordinates, their attributes and the remaining global attributes
        xr.testing.assert_identical(a, b)

    for table in ("paper_vs_reproduced.csv", "tmd_optimum.json"):
        ours, theirs = (r / "results" / "tables" / table for r in (runs.slurm, runs.local))
        assert ours.read_bytes() == theirs.read_bytes(), table

    figures = yaml.safe_load((runs.slurm / SMOKE).read_text())["figures"]
    for fig in figures:
        for ext in ("png", "pdf"):
            for run in (runs.slurm, runs.local):
                path = run / "results" / "figures" / f"{fig}.{ext}"
                assert path.is_file() and path.stat().st_size > 5000, path


@pytest.mark.slow
def test_every_job_is_one_slurm_job_sized_by_its_rule(runs):
    log = runs.slurm_log
    # the workflow profile is read on top of --profile (see the test above)
    assert "Using profiles profiles/slurm and workflow specific profile profiles/default" in log
    stats = _job_stats(log)
    submitted = _submissions(log)
    # every job went through sbatch but the local rules: the target (`study` from the root Snakefile,
    # `all` from workflow/Snakefile; it runs nothing) and `report` (localrule: it reads every result
    # and records the executor)
    local = stats.get("study", 0) + stats.get("all", 0) + stats.get("report", 0)
    assert len(submitted) == stats["total"] - local, (stats, submitted)
    for slurm_id, (job, info) in _slurm_records(runs).items():
        res = job["resources"]
        assert info["JobState"] == "COMPLETED", (slurm_id, job["rule"], info.get("JobState"))
        # sbatch -t from the rule's runtime, --mem from mem_mb, --cpus-per-task from threads
        assert _minutes(info["TimeLimit"]) == float(res["runtime"]), (job["rule"], info["TimeLimit"], res)
        assert info["MinMemoryNode"] == f"{res['mem_mb']}M", (job["rule"], info["MinMemoryNode"], res)
        assert info["NumCPUs"] == res["cpus_per_task"], (job["rule"], info["NumCPUs"], res)
        # the job runs its own Snakemake with this very interpreter (the .venv)
        script = _quiet("scontrol", "write", "batch_script", str(slurm_id), "-")
        if script is not None and script.returncode == 0:
            assert f"{sys.executable} -m snakemake" in script.stdout, script.stdout[:500]


@pytest.mark.slow
def test_jobs_starting_together_share_the_numba_cache(runs):
    """Each sweep job compiles its kernel on first use into NUMBA_CACHE_DIR, under the lock of
    impact.engine.paper.ensure_compiled: jobs starting together wait for each other, never write
    the cache at once, and load what the first one stored."""
    sweeps = [(dt.datetime.fromisoformat(info["StartTime"]), dt.datetime.fromisoformat(info["EndTime"]))
              for job, info in _slurm_records(runs).values() if job["rule"] == "sweep_curve"]
    events = sorted([(start, 1) for start, _ in sweeps] + [(end, -1) for _, end in sweeps])
    running = together = 0
    for _, step in events:
        running += step
        together = max(together, running)
    node_cpus = runs.times["slurm_node_cpus"] or 1
    if node_cpus >= 2 and len(sweeps) >= 2:
        assert together >= 2, f"no two sweep jobs ran at the same time: {sweeps}"
    print(f"\n[slurm] at most {together} sweep jobs ran at once on a node of {node_cpus} CPUs")

    # the jobs saw NUMBA_CACHE_DIR (sbatch --export=ALL) and compiled the kernels left out of it there
    cache = runs.numba_slurm
    assert (cache / "impact-jit.lock").is_file(), sorted(cache.glob("*"))
    for kernel in SLURM_KERNELS:
        assert list(cache.rglob(f"{kernel}*.nbi")) and list(cache.rglob(f"{kernel}*.nbc")), sorted(cache.rglob("*"))
    # and no job complained: neither its own log nor its SLURM log
    logs = list((runs.slurm / "results" / "logs").rglob("*.log"))
    logs += list((runs.slurm / ".snakemake" / "slurm_logs").rglob("*.log"))
    assert len(logs) >= 2 * len(sweeps)
    for path in logs:
        text = path.read_text(errors="replace")
        for bad in ("Traceback", "NumbaWarning", "NumbaError", "ERROR", "Error in rule"):
            assert bad not in text, f"{bad} in {path}:\n{text[-2000:]}"
    for path in sorted((runs.slurm / "results" / "logs" / "sweep_curve").glob("*.log")):
        done = re.findall(r"^(\S+ \S+) INFO done in (\S+ s)", path.read_text(), re.M)
        print(f"[slurm]   {path.stem}: finished {done[-1][0] if done else '?'}, "
              f"{done[-1][1] if done else '?'} in the job's script")
