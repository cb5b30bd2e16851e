"""The benchmarks' own code paths run: a benchmark is measured rarely, and a stage's signature can move under it
(bench_yield's collapse hunt called the IDA's damper design without the ida section for a turn)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def bench_yield():
    sys.path.insert(0, str(BENCH))  # as when run as a script: it imports bench_scene beside it
    spec = importlib.util.spec_from_file_location("bench_yield", BENCH / "bench_yield.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_collapse_hunt_from_the_bare_bracket_finds_the_hunts_bracket(bench_yield, monkeypatch):
    """On one far-field motion, each damper's hunt started at the bare archetype's bracket and the hunt from the
    first level bracket the same collapse intensity (their brackets overlap), the first in fewer runs or as many."""
    monkeypatch.setattr(bench_yield, "HUNT_MOTIONS", ("fema-farfield:1:a",))
    cases = bench_yield.collapse_hunt_cases()
    assert [c["case"].split(", ")[-1] for c in cases] == ["cid of 2 %", "pid of 2 %", "tmd of 2 %"]
    for case in cases:
        assert case["brackets_overlap"], case
        assert case["runs_from_bare"] <= case["runs_hunted"], case
