"""numba's on-disk cache: two processes starting at once must not race on it; a stale cache is dropped under the
compile lock, never by an import; a first compile is said on the terminal even from a job that logs to a file."""

from __future__ import annotations

import contextlib
import importlib
import io
import json
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest
from reference import HANG_GUARD_S

from impact.engine import jitcache

pytestmark = pytest.mark.slow


def test_two_processes_compiling_at_once_agree(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    cmd = [sys.executable, "-m", "impact.cli", "run", "--damper", "pid", "--gap-ratio", "1.0", "--periods", "20",
           "--average-from", "10"]
    procs = [subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    outs = [p.communicate(timeout=HANG_GUARD_S) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    results = [json.loads(out) for out, _ in outs]
    assert results[0] == results[1]
    # the cache was written once and is complete: a third process only loads it
    files = list((tmp_path / "cache").rglob("*.nbi"))
    assert files
    third = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert third.returncode == 0 and json.loads(third.stdout) == results[0]
    # a compile says so, once, on stderr: the process that compiled, not the one that waited and loaded, nor
    # a later one
    said = [err.count("impact: compiling the engine's paper loop for the PID") for _, err in outs]
    assert sorted(said) == [0, 1], [err for _, err in outs]
    assert "compiling" not in third.stderr


_SAVING = """
import sys
sys.path.insert(0, sys.argv[1])
import impact.engine.jitcache  # noqa: F401  (serialises numba's index saves)
from numba.core import caching
serialised = caching.IndexDataCacheFile.save
def announced(self, key, data):
    print("saving", flush=True)
    serialised(self, key, data)
caching.IndexDataCacheFile.save = announced
import twice
print(twice.twice._cache._cache_path, flush=True)
sys.stdin.readline()
twice.twice(1)
print("saved", flush=True)
"""


def test_a_save_to_a_cache_index_waits_for_the_folder_lock(tmp_path):
    """Kernels compiling side by side share the steps they call, so two processes may save one function's index at
    once; numba reads, extends and rewrites it, so each save must wait for the folder's lock (jitcache)."""
    import filelock

    (tmp_path / "twice.py").write_text("import numba\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n")
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    proc = subprocess.Popen([sys.executable, "-c", _SAVING, str(tmp_path)], env=env, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    folder = Path(proc.stdout.readline().strip())
    folder.mkdir(parents=True, exist_ok=True)
    try:
        with filelock.FileLock(folder / jitcache.FOLDER_LOCK):
            proc.stdin.write("go\n")
            proc.stdin.flush()
            # compiled, the child is at its save, which takes milliseconds unlocked, however loaded the machine
            assert proc.stdout.readline().strip() == "saving"
            with pytest.raises(subprocess.TimeoutExpired):
                proc.wait(timeout=2)
            assert not list(folder.glob("*.nbi"))
        assert proc.communicate(timeout=HANG_GUARD_S)[0].strip() == "saved"
    finally:
        proc.kill()
    assert proc.returncode == 0 and list(folder.glob("twice.twice-*.nbi"))


def _fake_dispatcher(folder):
    return SimpleNamespace(_cache=SimpleNamespace(_cache_path=str(folder)))


def _plant(folder, names):
    folder.mkdir(parents=True, exist_ok=True)
    for name in names:
        (folder / name).write_text("")


def test_a_stale_cache_is_dropped_under_the_lock_once(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "locks"))
    kernels = tmp_path / "kernels"
    _plant(kernels, ["loop.run-1.py311.nbi", "loop.run-1.py311.1.nbc", "impact-sources-0123.stamp", "notes.txt"])
    with jitcache.compile_lock("test", fresh=(_fake_dispatcher(kernels),)):
        pass
    left = sorted(p.name for p in kernels.iterdir())
    assert left == [f"{jitcache.STAMP}-{jitcache.sources_digest()}.stamp", "notes.txt"]
    # kernels written for the current sources stay: the stamp says they are fresh
    _plant(kernels, ["loop.run-1.py311.nbi"])
    with jitcache.compile_lock("test", fresh=(_fake_dispatcher(kernels),)):
        pass
    assert (kernels / "loop.run-1.py311.nbi").exists()


_CACHE_FOLDERS = """
import json
from impact.engine.paper_loop import run
from impact.engine.scene_loop import run_scene
from impact.engine.sampler import paper_samples
print(json.dumps([f._cache._cache_path for f in (run, run_scene, paper_samples)]))
"""


def test_importing_the_kernels_deletes_nothing(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def imported():
        out = subprocess.run([sys.executable, "-c", _CACHE_FOLDERS], env=env, capture_output=True, text=True,
                             check=True, timeout=HANG_GUARD_S)
        return json.loads(out.stdout)

    planted = []
    for folder in map(Path, imported()):
        _plant(folder, ["stale.run-1.py311.nbi", "impact-sources-0123.stamp"])
        planted += [folder / "stale.run-1.py311.nbi", folder / "impact-sources-0123.stamp"]
    imported()
    assert all(p.exists() for p in planted)


def test_a_first_compile_is_said_on_the_terminal_from_a_job_logging_to_a_file(tmp_path, monkeypatch, capfd):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    log = io.StringIO()
    with contextlib.redirect_stderr(log):  # as outputs.job_log.logged does for a workflow job
        with jitcache.compile_lock("test-kernel", "a test kernel"):
            pass
    assert "compiling a test kernel" in log.getvalue()
    assert "compiling a test kernel" in capfd.readouterr().err


def test_the_stamp_reads_every_module_a_kernel_is_compiled_from_and_not_the_python_around_them():
    """A module of the engine defining a compiled function, or holding what one reads (a function, a constant, a
    bundle's type), is in the digest; the dispatch and the scene's arrays are not, so editing them keeps the cache."""
    from numba.core.registry import CPUDispatcher

    stamped = {path.stem for path in jitcache.kernel_sources()}
    engine = {path.stem for path in jitcache.CORE.glob("*.py")}
    for name in engine:
        module = importlib.import_module(f"impact.engine.{name}")
        kernels = [value for value in vars(module).values()
                   if isinstance(value, CPUDispatcher) and value.py_func.__module__ == module.__name__]
        if kernels:
            assert name in stamped, f"{name} defines kernels but is not stamped"
        if name in stamped:  # what a stamped module reads from the engine is stamped too
            read = {getattr(value, "__module__", None) or getattr(value, "__name__", "")
                    for value in vars(module).values()}
            read = {mod.split(".")[2] for mod in read if mod.startswith("impact.engine.")}
            assert read <= stamped | {name}, f"{name} reads {sorted(read - stamped)}, not stamped"
    assert {"scene_loop", "segment", "clear_step", "events", "layout", "bundles", "paper_loop"} <= stamped
    assert stamped.isdisjoint({"run", "scenes", "spectra", "paper", "diagnostics", "jitcache", "__init__"})
