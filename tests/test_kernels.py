"""One kernel set for the study (impact.kernels): chosen before numpy loads, and what it buys.

Kernel sets round differently (an AVX-512 machine's SkylakeX kernels against an AVX2 machine's Haswell ones),
and the modal decomposition under every scene goes through them.  The study holds OpenBLAS and numpy's loops to
one set, so the same set gives the same bits in any process; another set moves a value no further than its own
round-off sensitivity, measured as the spread a 1e-15 change of the record's scale gives it.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from reference import HANG_GUARD_S

from impact import kernels

HERE = Path(__file__).parent
#: OpenBLAS's generic x86-64 kernels (it reports them as Katmai): every x86-64 CPU runs them
GENERIC = "Prescott"
OPENBLAS, NUMPY = kernels.PINS["openblas"], kernels.PINS["numpy"]
THREADS = kernels.THREADS
#: how kernels() names one OpenBLAS under the study's set and thread count
STUDY_BLAS = f"openblas {OPENBLAS.value} {THREADS.value} thread"


@pytest.fixture
def any_cpu(monkeypatch):
    monkeypatch.setattr(kernels, "_cpu_can_run_it", lambda: True)


def test_the_pinned_sets_are_chosen_unless_another_is_named(any_cpu):
    env = {}
    assert kernels.apply(env) == {"openblas": OPENBLAS.value, "numpy": NUMPY.value}
    assert env == {OPENBLAS.variable: OPENBLAS.value, NUMPY.variable: NUMPY.value, THREADS.variable: THREADS.value}
    assert kernels.pinned(env)
    env = {OPENBLAS.override: "SkylakeX", OPENBLAS.variable: "Haswell"}
    assert kernels.apply(env)["openblas"] == "SkylakeX" and env[OPENBLAS.variable] == "SkylakeX"
    assert not kernels.pinned(env)


def test_native_leaves_the_choice_to_the_library_not_to_the_machines_environment(any_cpu):
    env = {OPENBLAS.override: "native", OPENBLAS.variable: "Haswell", NUMPY.override: "NATIVE"}
    assert kernels.apply(env) == {"openblas": None, "numpy": None}
    assert OPENBLAS.variable not in env and NUMPY.variable not in env


def test_openblas_runs_one_thread_unless_another_count_is_named():
    """Whatever the machine's environment says (a thread count rounds: docs/performance.md) and whatever the CPU."""
    env = {THREADS.variable: "8"}
    kernels.apply(env)
    assert env[THREADS.variable] == THREADS.value == "1" and kernels.threads(env) == "1"
    env = {THREADS.override: "2", THREADS.variable: "8"}
    kernels.apply(env)
    assert env[THREADS.variable] == "2" and not kernels.pinned(env)
    env = {THREADS.override: "native", THREADS.variable: "8"}
    kernels.apply(env)
    assert THREADS.variable not in env and kernels.threads(env) is None


def test_every_job_of_the_study_runs_the_pinned_thread_count():
    """Snakemake sets OpenBLAS's threads to a job's own (its rule's `threads`, 1 where unsaid): a rule asking for
    more would round its matrices otherwise than the tests and the command line do."""
    asked = {}
    for smk in sorted((HERE.parent / "workflow" / "rules").glob("*.smk")):
        for block in re.split(r"(?m)^(?=rule )", smk.read_text())[1:]:
            asked[block.split()[1].rstrip(":")] = re.findall(r"(?m)^\s+threads:\s*(.+?)\s*$", block)
    assert len(asked) > 30
    assert {rule: said for rule, said in asked.items() if said not in ([], [THREADS.value])} == {}


def test_a_cpu_that_cannot_run_the_pinned_sets_is_left_to_the_libraries(monkeypatch, tmp_path):
    cpuinfo = tmp_path / "cpuinfo"
    monkeypatch.setattr(kernels.platform, "machine", lambda: "x86_64")
    cpuinfo.write_text("processor : 0\nflags : fpu sse sse2 avx\n")
    assert not kernels._cpu_can_run_it(str(cpuinfo))
    cpuinfo.write_text(f"processor : 0\nflags : fpu sse sse2 avx {' '.join(kernels.NEEDS)}\n")
    assert kernels._cpu_can_run_it(str(cpuinfo))
    monkeypatch.setattr(kernels.platform, "machine", lambda: "aarch64")
    assert not kernels._cpu_can_run_it(str(cpuinfo))


def test_this_test_run_computes_with_the_pinned_sets():
    """conftest.py chose the sets before numpy loaded: the libraries report them (where the CPU runs them)."""
    if not kernels.pinned():
        pytest.skip(f"this run computes with {kernels.chosen()}")
    loops, blas = kernels.kernels().split("; ")
    assert loops == f"numpy {NUMPY.value}" and set(blas.split(", ")) == {STUDY_BLAS}


def _values(**overrides: str) -> dict:
    env = dict(os.environ) | {kernels.PINS[library].override: value for library, value in overrides.items()}
    kernels.apply(env)  # as the workflow and the tests do, before the process loads numpy
    proc = subprocess.run([sys.executable, str(HERE / "kernel_values.py")], env=env, capture_output=True, text=True,
                          timeout=HANG_GUARD_S)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout)


@pytest.fixture(scope="module")
def pinned():
    if not kernels.pinned({}):
        pytest.skip("this CPU does not run the pinned kernel sets")
    return _values()


@pytest.mark.slow
def test_the_pinned_sets_give_the_same_bits_in_another_process(pinned):
    again = _values()
    both = f"numpy {NUMPY.value}; {STUDY_BLAS}, {STUDY_BLAS}"
    assert again["kernels"] == pinned["kernels"] == both
    assert {k: v["value"] for k, v in again["values"].items()} == {k: v["value"] for k, v in pinned["values"].items()}


@pytest.mark.slow
def test_other_kernels_move_each_value_within_its_round_off_sensitivity(pinned):
    """OpenBLAS's generic kernels (which every x86-64 CPU runs) and numpy's loops as the CPU picks them, against
    the pinned sets: each value within three times the larger spread of its round-off ensemble, or 1e-12 of its
    size where that ensemble does not move it."""
    other = _values(openblas=GENERIC, numpy=kernels.NATIVE)
    assert OPENBLAS.value not in other["kernels"]
    moved = 0
    for key, ours in pinned["values"].items():
        theirs = other["values"][key]
        sensitivity = max(ours["spread"], theirs["spread"], 1e-12 * abs(ours["value"]))
        assert abs(theirs["value"] - ours["value"]) <= 3.0 * sensitivity, (key, ours, theirs)
        moved += theirs["value"] != ours["value"]
    # the kernel sets do round differently here: the test compares two different computations
    assert moved > 0


def test_a_script_runs_under_the_pinned_sets(tmp_path):
    """python -m impact.kernels SCRIPT ARGS: the script sees its arguments and computes with the pinned sets."""
    script = tmp_path / "script.py"
    script.write_text("import sys\nfrom impact import kernels\nimport numpy\n"
                      "print(sys.argv[1:], kernels.pinned(), kernels.kernels())\n")
    env = {k: v for k, v in os.environ.items() if k not in (OPENBLAS.variable, NUMPY.variable, THREADS.variable)}
    proc = subprocess.run([sys.executable, "-m", "impact.kernels", str(script), "--quick"], env=env,
                          capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert proc.returncode == 0, proc.stderr
    if not kernels.pinned({}):
        pytest.skip("this CPU does not run the pinned kernel sets")
    assert proc.stdout.startswith(f"['--quick'] True numpy {NUMPY.value}; {STUDY_BLAS}")
