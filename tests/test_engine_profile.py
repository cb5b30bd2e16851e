"""tools/engine_profile.py names the engine's compiled functions in a perf profile: its reading of numba's symbols,
its perf map and its sum of perf's report per function (perf itself is not needed here)."""

from __future__ import annotations

from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[1] / "tools" / "engine_profile.py"

CLEAR_STEPS = "_ZN6impact6engine10clear_step11clear_stepsB4v530B40c8tJTIeFIjxB2IKSgI4CrvSCKg1MMfAwK4LIaQIAE5Tuple"


@pytest.mark.parametrize("symbol, name", [
    (CLEAR_STEPS, "impact.engine.clear_step.clear_steps"),
    ("_ZN6impact6engine10scene_loop9run_sceneB4v388B40c8tJTIeFIjxB2IKSgI4CrvSCKg1MMfAwK4LIaQIAE6Record",
     "impact.engine.scene_loop.run_scene"),
    ("_ZN5numba2np8arrayobj13ol_empty_like12_3clocals_3e4implB3v22E5Array",
     "numba.np.arrayobj.ol_empty_like.<locals>.impl"),
    ("__sincos_fma", "__sincos_fma"),
])
def test_a_numba_symbol_reads_as_its_dotted_name(tool, symbol, name):
    assert tool.demangle(symbol) == name


def test_the_map_gives_each_function_the_span_to_the_next(tool):
    lines = tool.perf_map({0x2000: CLEAR_STEPS, 0x1000: "helper"}).splitlines()
    assert lines == ["1000 1000 helper", "2000 1000 impact.engine.clear_step.clear_steps"]


def test_the_shares_sum_each_functions_specialisations(tool):
    report = "\n".join([
        "    28.55%  [.] " + CLEAR_STEPS,
        "     1.50%  [.] " + CLEAR_STEPS.replace("v530", "v531"),
        "     5.31%  [.] __sincos_fma",
        "     0.40%  [k] exc_page_fault",
        "# a comment line",
    ])
    shares = tool.shares(report)
    assert shares["impact.engine.clear_step.clear_steps"] == pytest.approx(30.05)
    assert shares["__sincos_fma"] == pytest.approx(5.31)
    assert sum(shares.values()) == pytest.approx(35.76)


def test_a_case_is_found_by_the_start_of_its_name_and_an_unknown_one_names_the_cases(tool):
    scene, peaks, window = tool.bench_case("3 storeys, CID at the roof")
    assert [d.kind for d in scene.dampers] == ["cid"] and window
    with pytest.raises(SystemExit, match="1 storey, bare"):
        tool.bench_case("no such case")
