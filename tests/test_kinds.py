"""The damper kinds' registry (impact.model.kinds): a kind made of parts the engine knows is one entry.

The toy kind here, a TMD with stops (a tuned mass whose stroke walls end), is registered in the test alone: no
other file of the package names it.  The study's TMD gets its stops from a Damper field instead (stroke_limit),
and the engine sees the same unit either way.
"""

import ast
import tokenize
from pathlib import Path

import numpy as np
import pytest

from impact.engine.run import simulate
from impact.model import kinds
from impact.model.building import Building
from impact.model.kinds import DamperKind
from impact.model.params import ParameterError, Protocol
from impact.model.scene import Damper, Harmonic, Scene

STOPPED_TMD = DamperKind("stopped_tmd", "tuned mass damper with stops", walls=True, spring=True, dashpot=True,
                         slides=False, paper=False)


@pytest.fixture
def stopped_tmd(monkeypatch):
    monkeypatch.setitem(kinds.KINDS, STOPPED_TMD.name, STOPPED_TMD)
    return STOPPED_TMD.name


def _scene(kind, gap, building=Building.uniform(3, 1.0, 0.02)):
    mass = 0.03 * building.total_mass
    omega = building.omega1
    load = Harmonic(0.02 * building.total_mass * omega ** 2 * 0.05, omega, floor=1)
    damper = Damper(kind, mass, gap=gap, e=0.6, tuning=0.97, damping=0.05)
    return Scene(building, (damper,), load, duration=20.0, start="centre")


def test_the_registry_is_what_the_model_checks_against(stopped_tmd):
    assert stopped_tmd in kinds.damper_kinds() and stopped_tmd in kinds.impact_kinds()
    with pytest.raises(ParameterError, match="nu is only defined for kind 'cid'"):
        Damper(stopped_tmd, 1.0, gap=0.1, nu=0.1)
    with pytest.raises(ParameterError, match="tuning"):
        Damper(stopped_tmd, 1.0, gap=0.1, tuning=0.0)  # a spring's tuning is above 0
    with pytest.raises(ParameterError, match="gap is not defined for kind 'tmd'"):
        Damper("tmd", 1.0, gap=0.1)


def test_a_kind_registered_alone_runs_and_is_the_tmd_while_its_stops_are_out_of_reach(stopped_tmd):
    """Stops wider than the TMD's stroke are never struck: the run is the TMD's, to the last bits."""
    free = simulate(_scene("tmd", 0.0), measures=("peaks",))
    far = simulate(_scene(stopped_tmd, 100.0 * free.peak_strokes[0]), measures=("peaks",))
    assert far.impacts == 0
    np.testing.assert_allclose(far.final_q, free.final_q, rtol=0, atol=1e-12 * np.max(np.abs(free.final_q)))
    assert far.peak_roof_displacement == pytest.approx(free.peak_roof_displacement, rel=1e-12)


def test_a_kind_registered_alone_strikes_its_stops_within_the_engines_promises(stopped_tmd):
    """Stops at half the free stroke: the mass strikes them, its stroke stays within them, the energy balances."""
    free = simulate(_scene("tmd", 0.0), measures=("peaks",))
    gap = free.peak_strokes[0]  # walls at +-half the free stroke
    stopped = simulate(_scene(stopped_tmd, gap), measures=("peaks",))
    diag = stopped.diagnostics
    assert stopped.impacts > 10
    assert stopped.peak_strokes[0] <= 0.5 * gap * (1 + 1e-9)
    assert abs(diag["energy_residual"]) < 1e-9
    assert diag["max_penetration"] <= 1e-9 * gap
    assert diag["impact_losses"] > 0.0  # e = 0.6: each strike loses (1 - e^2) of its relative kinetic energy


def test_a_tmd_with_a_stroke_limit_is_a_unit_with_stops_to_the_bit(stopped_tmd):
    """Damper.stroke_limit gives a wall-less kind end stops at +-limit: the engine runs the same unit as the kind
    registered with walls a gap of twice the limit, so every number is the same."""
    free = simulate(_scene("tmd", 0.0), measures=("peaks",))
    limit = 0.5 * free.peak_strokes[0]
    scene = _scene(stopped_tmd, 2.0 * limit)
    (toy,) = scene.dampers
    tmd = Damper("tmd", toy.mass, e=toy.e, tuning=toy.tuning, damping=toy.damping, stroke_limit=limit)
    stopped = simulate(Scene(scene.building, (tmd,), scene.load, duration=scene.duration, start="centre"),
                       measures=("peaks", "impacts"))
    toy_run = simulate(scene, measures=("peaks", "impacts"))
    assert stopped.impacts == toy_run.impacts > 10
    assert stopped.peak_strokes[0] <= limit * (1 + 1e-9)
    np.testing.assert_array_equal(stopped.final_q, toy_run.final_q)
    assert stopped.diagnostics["energy_residual"] == toy_run.diagnostics["energy_residual"]


@pytest.mark.parametrize("fields, message", [
    (dict(kind="cid", gap=0.1, stroke_limit=0.05), "stroke_limit is not defined for kind 'cid'"),
    (dict(kind="tmd", stroke_limit=0.0), r"stroke_limit = 0.0 is out of range: allowed \(0.0, "),
    (dict(kind="tmd", stroke_limit=-1.0), "stroke_limit"),
])
def test_a_stroke_limit_is_refused_by_name_where_it_means_nothing(fields, message):
    kind = fields.pop("kind")
    with pytest.raises(ParameterError, match=message):
        Damper(kind, 1.0, **fields)


def test_a_stage_reads_a_kind_by_its_parts(stopped_tmd):
    """The robustness stage varies, builds and starts a design by what its kind is made of, not by its name: the
    toy kind has the TMD's dashpot and the CID's walls, so both its damping and its restitution vary, its units
    start where the design puts them, and its stroke is not capped by damping (its walls cap it)."""
    from impact.stages.robustness.designs import Design, applicable
    from impact.stages.robustness.runs import capped_tmd_damping, design_scene

    assert applicable(stopped_tmd) == ("scale", "drift", "damping", "e")
    assert applicable("cid") == ("scale", "drift", "e") and applicable("tmd") == ("scale", "drift", "damping")
    design = Design(stopped_tmd, 0.02, 0.02, gap_ratio=1.0, e=0.6, tuning=0.97, damping=0.05, start="left")
    scene = design_scene(design, 1.0, Protocol(periods=4.0, average_from=2.0))
    (damper,) = scene.dampers
    assert (damper.kind, damper.gap, damper.tuning, scene.start) == (stopped_tmd, design.gap, 0.97, "left")
    with pytest.raises(ValueError, match="without walls"):
        capped_tmd_damping(design, [1.0], Protocol(), stroke_cap=1.0)


def _kinds_named_in_code(path):
    """(line, name) of every string in the file's code (docstrings and comments aside) that is a kind's name."""
    names = set(kinds.damper_kinds())
    with open(path, "rb") as f:
        tokens = list(tokenize.tokenize(f.readline))
    found = []
    for tok in tokens:
        if tok.type == tokenize.STRING:
            try:
                value = ast.literal_eval(tok.string)
            except ValueError:
                continue  # an f-string
            if value in names:
                found.append((tok.start[0], value))
    return found


def test_no_module_names_a_kind_but_the_registry():
    """A branch on a kind reads its parts (KINDS[name].walls, ...) and a plan that names one of the study's kinds
    reads model.kinds' CID, PID or TMD: no other module or workflow script spells a kind's name, so a new kind
    is one entry in the registry."""
    root = Path(kinds.__file__).parents[3]
    files = [p for p in (*root.glob("src/impact/**/*.py"), *root.glob("workflow/scripts/*.py"))
             if p != Path(kinds.__file__)]
    spelt = [f"{p.relative_to(root)}:{line}: {name!r}" for p in files for line, name in _kinds_named_in_code(p)]
    assert spelt == []
