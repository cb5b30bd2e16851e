"""The compiled kernels' cache: a stale one is dropped under the compile lock, never by an import."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

from impact.engine import jitcache


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
from impact.stages.validation.paper_model import _model_samples
print(json.dumps([f._cache._cache_path for f in (run, run_scene, _model_samples)]))
"""


def test_importing_the_kernels_deletes_nothing(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))

    def imported():
        out = subprocess.run([sys.executable, "-c", _CACHE_FOLDERS], env=env, capture_output=True, text=True,
                             check=True, timeout=3600)
        return json.loads(out.stdout)

    planted = []
    for folder in map(Path, imported()):
        _plant(folder, ["stale.run-1.py311.nbi", "impact-sources-0123.stamp"])
        planted += [folder / "stale.run-1.py311.nbi", folder / "impact-sources-0123.stamp"]
    imported()
    assert all(p.exists() for p in planted)
