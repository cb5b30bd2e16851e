"""numba's on-disk cache: two processes starting at once must not race on it."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from reference import HANG_GUARD_S

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
