"""The package's compiled functions take named bundles (impact.engine.bundles), not dozens of positional arrays.

The steps on every segment of a scene run take one numba structref (bundles.SegmentWork): a namedtuple
of arrays there cost 8 to 31 % of a run, the structref nothing measurable (docs/architecture.md, "How the scene
loop's arrays travel").  Every compiled function of the package takes ten parameters or fewer.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

import impact
import impact.engine
from impact.engine import bundles

PACKAGE = Path(impact.__file__).parent
ENGINE = Path(impact.engine.__file__).parent
MOST_PARAMETERS = 10


def compiled_functions(folder: Path):
    """(file path below folder, function name, number of parameters, inlined) of every @njit function there."""
    for path in sorted(folder.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef) and any("njit" in ast.unparse(d) for d in node.decorator_list):
                yield str(path.relative_to(folder)), node.name, len(node.args.args), "inline='always'" in \
                    " ".join(ast.unparse(d) for d in node.decorator_list)


def test_every_compiled_function_takes_at_most_ten_parameters():
    found = list(compiled_functions(PACKAGE))
    # the walk sees every layer with numba: the engine and the rig's own kernels, and no stage compiles any
    assert {f.split("/")[0] for f, *_ in found} == {"engine", "rig"}
    assert [(f, name, n) for f, name, n, _ in found if n > MOST_PARAMETERS] == []


#: the engine's modules whose steps numba inlines (inline='always'): clear_step's tests, which called made the bare
#: run 3.5 times slower, and the paper loop's.  Every other step is a compiled call of its own: numba types an inlined
#: step again at each call site, which made `impact compile` take three times as long (docs/performance.md,
#: "Compiling the loop's steps as calls")
INLINING_MODULES = {"clear_step.py", "paper_loop.py"}


def test_the_per_segment_steps_are_compiled_calls_and_take_the_segment_work():
    """The steps run on every segment are compiled calls, not inlined, and reach their arrays through the one
    SegmentWork, whose fields are the names they read; only the modules named above inline a step."""
    steps = {"build_segment", "search_constraints", "_search_unit", "_search_storey", "_search_yielding_storey",
             "_storey_clear", "_turning_clear", "_modal_reach", "_storey_row", "_band_exit", "_sign_exit",
             "integrate_segment", "integrate_energy", "integrate_modal",
             "monitor_modal", "monitor_row", "curvature_bound", "window_square", "move_to_end"}
    functions = list(compiled_functions(ENGINE))
    found = {name: inline for _, name, _, inline in functions}
    assert steps <= set(found) and not any(found[name] for name in steps)
    assert {path for path, _, _, inline in functions if inline} == INLINING_MODULES
    read = set()
    for path in ENGINE.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef) and node.name in steps:
                assert node.args.args[0].arg == "w", node.name
                read |= {a.attr for a in ast.walk(node) if isinstance(a, ast.Attribute)
                         and isinstance(a.value, ast.Name) and a.value.id == "w"}
    assert read <= set(bundles.SEGMENT_WORK_FIELDS)
    assert {"kap", "C", "P", "diag", "mon_peak", "wf", "wc", "lam", "cache"} <= read


def test_a_synthetic_engine_folder_with_a_long_signature_is_caught(tmp_path):
    """The walk is not blind: a compiled function with eleven parameters in a folder of its own is found."""
    (tmp_path / "long.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef long(a, b, c, d, e, f, g, h, i, j, k):\n    return a\n")
    assert [(name, n) for _, name, n, _ in compiled_functions(tmp_path)] == [("long", 11)]


def test_a_bundle_is_read_by_name_and_by_position_alike():
    """The compiled code reads some bundles by field and unpacks others by position: the two must agree."""
    units = bundles.UnitArrays(*(np.full(2, float(i)) for i in range(6)))
    kind, floor, mass, load, gap, restitution = units
    assert (units.kind[0], units.gap[0], units.restitution[0]) == (kind[0], gap[0], restitution[0]) == (0.0, 4.0, 5.0)
    assert bundles.RunState._fields[:7] == ("mode", "side", "sigma", "offset", "escape", "escape_v", "check")


def test_a_borrowed_view_is_its_owners_memory():
    """bundles.borrowed: the same data, shape and strides (writes reach the owner), for 1 to 3 dimensions and a
    strided view; the scene loop's arrays travel borrowed, so a wrong stride here would move every result."""
    from numba import njit

    @njit
    def write_through(a, i, value):
        view = bundles.borrowed(a)
        view.flat[i] = value
        return view.shape, view.strides, view.sum()

    for a in (np.arange(5.0), np.arange(12.0).reshape(3, 4), np.arange(24.0).reshape(2, 3, 4)[:, ::2]):
        shape, strides, total = write_through(a, 1, 100.0)
        assert (shape, strides) == (a.shape, a.strides)
        assert a.flat[1] == 100.0 and total == a.sum()


def test_a_borrowed_bundle_is_the_same_bundle_of_its_owners_memory():
    """bundles.borrowed of a bundle: every array of it, nested bundles too, a view of its owner (writes reach it),
    numbers kept, and None stays None, so the scene loop borrows a bundle or an absent optional part in one call."""
    from numba import njit

    @njit
    def write_through(scene, absent, pair):
        s, none, p = bundles.borrowed(scene), bundles.borrowed(absent), bundles.borrowed(pair)
        s.building.stiffness[0, 1] = 5.0
        s.units.gap[1] = 7.0
        p[0][2] = 9.0
        return s.p.sum(), s.units.kind.sum(), none is None, p[1]

    units = bundles.UnitArrays(*(np.full(2, float(i)) for i in range(6)))
    scene = bundles.SceneArrays(np.arange(3.0), bundles.BuildingArrays(np.ones(2), np.eye(2), np.eye(2)), units,
                                np.ones(2), bundles.MonitorArrays(np.ones((1, 2)), np.zeros(1, dtype=np.int64),
                                                                  np.ones(1), np.ones(1),
                                                                  np.zeros(1, dtype=np.int64)))
    pair = (np.zeros(3), 4)
    assert write_through(scene, None, pair) == (3.0, 0.0, True, 4)
    assert scene.building.stiffness[0, 1] == 5.0 and units.gap[1] == 7.0 and pair[0][2] == 9.0


ALLOCATIONS_PER_RUN = """
import dataclasses, json
from numba.core.runtime import rtsys
from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.records import load_record
from impact.model.scene import Damper, GroundMotion, Scene

three = Building.uniform(3, 1.0, 0.02)
whole = GroundMotion.from_record(load_record("elcentro"), pga_g=0.35)
out = {}
for units in (1, 4):
    damper = Damper("cid", 0.02 * three.total_mass, gap=0.05, e=0.5, units=units)
    for samples in (len(whole.accel) // 2, len(whole.accel)):
        scene = Scene(three, (damper,), dataclasses.replace(whole, accel=whole.accel[:samples].copy()))
        simulate_scene(scene)  # the first run of a process loads the kernel
        before = rtsys.get_allocation_stats().alloc
        impacts = simulate_scene(scene).impacts
        out[f"{units} {samples}"] = (impacts, rtsys.get_allocation_stats().alloc - before)
print(json.dumps(out))
"""


def test_an_impact_allocates_nothing():
    """A run allocates its workspace once, and nothing at an impact: numba's allocation count (NRT statistics) of
    a CID run over half of El Centro is that of the run over all of it, with 93 impacts more (154 and 247), in one
    unit and in four.  An impact allocated eleven arrays before (the floor's impulses' scratch, a cut step's rows of
    powers and of the ramp form): 1,831 and 2,838 allocations in the two runs."""
    env = {**os.environ, "NUMBA_NRT_STATS": "1"}
    proc = subprocess.run([sys.executable, "-c", ALLOCATIONS_PER_RUN], env=env, capture_output=True, text=True,
                          check=True)
    runs = json.loads(proc.stdout)
    for units in (1, 4):
        (few, half), (many, whole) = (runs[key] for key in runs if key.startswith(f"{units} "))
        assert many > few + 50 and half == whole, runs
