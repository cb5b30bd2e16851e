"""One entry point to the engine: ``simulate(scene, measures=...)`` picks the loop that runs it.

    result = simulate(scene)                                  # amplitude, impacts, diagnostics
    result = simulate(scene, measures=("amplitude", "peaks"))  # and the certified peaks

:data:`LOOPS` is the dispatch table, tried in order: the first loop that can run the scene and
measure what is asked runs it.  The paper loop (:mod:`.paper_loop`) runs the paper's one-storey,
one-unit harmonic case in model units, several times faster (``benchmarks/bench_loops.py``);
the scene loop (:mod:`.scene_loop`) runs every scene.  Both return a :class:`~.scenes.SceneResult`;
what a loop does not measure is NaN there, and ``result.loop`` names the loop that ran.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from impact.engine import layout as L
from impact.engine import paper
from impact.engine import paper_loop as K
from impact.engine.diagnostics import read_diagnostics
from impact.engine.scenes import PEAK_GROUPS, SceneResult, simulate_scene
from impact.model.params import ParameterError, System
from impact.model.scene import Harmonic, Scene

#: what a run can measure: the window's amplitude (sqrt 2 RMS of the roof), the impacts and diagnostics
#: with the final state, the certified peaks of every monitor (roof, drifts, strokes) or of the drifts or the
#: strokes alone, impact records and the state at requested times
MEASURES = ("amplitude", "impacts", "peaks", "drifts", "strokes", "records", "samples")
DEFAULT_MEASURES = ("amplitude", "impacts")
PAPER_MEASURES = frozenset(("amplitude", "impacts"))


@dataclass(frozen=True)
class Loop:
    """A loop of the engine: whether it runs a scene with these measures, and the run."""

    fits: Callable[[Scene, frozenset], bool]
    run: Callable[..., SceneResult]


def as_paper_system(scene: Scene) -> System | None:
    """The scene as the paper loop's System, when it is the paper's case in model units; None otherwise.

    The paper's case: one storey of mass 1 and stiffness 1 (omega = 1, time in radians of the structure),
    one CID or undamped PID unit, a harmonic force on that storey, every unit starting at rest in the
    centre or on a wall.  Every number is taken as the scene holds it, so a scene built by
    :func:`impact.model.scene.paper_scene_from_system` runs exactly the System it was built from.
    """
    b = scene.building
    if not b.is_elastic:
        return None  # the paper loop's storey is linear
    if b.storeys != 1 or b.masses[0] != 1.0 or b.storey_stiffness[0] != 1.0 or len(scene.dampers) != 1:
        return None
    d = scene.dampers[0]
    load = scene.load
    if not d.kind_spec.paper or d.units != 1 or d.damping != 0.0 or d.floor not in (None, 1):
        return None
    if not isinstance(load, Harmonic) or load.floor not in (None, 1) or scene.unit_starts is not None:
        return None
    if b.damping[0, 0] != 2.0 * b.zeta:
        return None  # the paper's damping is C = 2 beta
    return System(d.kind, mu=d.mass, beta=b.zeta, e=d.e, gap=d.gap, rp=d.tuning if d.kind_spec.spring else 0.0,
                  force_ratio=load.amplitude, phase=load.phase, nu=d.nu)


def _paper_fits(scene: Scene, measures: frozenset) -> bool:
    return measures <= PAPER_MEASURES and as_paper_system(scene) is not None


def _run_paper(scene: Scene, measures: frozenset, record: int, times) -> SceneResult:
    system = as_paper_system(scene)
    r = scene.load.omega
    paper.check_resonance(system, r)
    z0, code = paper.initial_state(system, scene.start)
    p = paper.run_parameters(system, r, scene.t_end, scene.t_window, scene.max_events_per_period,
                             max_events=scene.event_budget)
    fric = np.array([system.nu * scene.gravity]) if system.nu > 0.0 else None
    paper.ensure_compiled(system.kind, fric is not None)
    diag = np.zeros(L.NDIAG)
    z_out = np.zeros(4)
    K.run(p, z0, int(code), paper.pid_data(system, r), fric, np.zeros((0, L.NREC)), diag, z_out)
    amp, span, complete = paper.window_amplitude(diag, scene.t_window)
    nan = math.nan
    return SceneResult(
        scene=scene, peak_roof_displacement=nan, peak_roof_displacement_time=nan,
        rms_roof_displacement=math.sqrt(diag[L.D_X2WIN] / span) if complete else nan,
        peak_roof_acceleration=nan, peak_interstorey_drift=nan, peak_drifts=np.full(1, nan),
        peak_strokes=np.full(1, nan), impacts=int(diag[L.D_IMPACTS]), diagnostics=read_diagnostics(diag),
        final_q=z_out[[0, 2]].copy(), final_v=z_out[[1, 3]].copy(), amplitude=amp, window_span=float(span),
        loop="paper")


def _run_scene(scene: Scene, measures: frozenset, record: int, times) -> SceneResult:
    return simulate_scene(scene, record=record, times=times, peaks=peak_groups(measures), window=has_window(measures))


def has_window(measures: frozenset) -> bool:
    """Whether the measures read the window's square of the roof: the amplitude, or the roof's RMS that "peaks"
    reports with its peaks.  A run asked for neither (the collapse stage's: impacts and drifts) integrates no
    window, and its amplitude and RMS are NaN."""
    return "amplitude" in measures or "peaks" in measures


def peak_groups(measures: frozenset) -> tuple:
    """The monitors' groups (scenes.PEAK_GROUPS) whose peaks the measures ask the scene loop to certify: every
    group for "peaks", else those named ("drifts", "strokes"); a group not asked costs nothing and reads NaN."""
    return PEAK_GROUPS if "peaks" in measures else tuple(g for g in PEAK_GROUPS if g in measures)


#: the loops, tried in order (the fast special case first)
LOOPS = {"paper": Loop(_paper_fits, _run_paper), "scene": Loop(lambda scene, measures: True, _run_scene)}


def simulate(scene: Scene, measures=DEFAULT_MEASURES, *, record: int = 0, times=None) -> SceneResult:
    """Run a scene on the engine's first loop (:data:`LOOPS`) that measures what is asked.

    measures: names from :data:`MEASURES`, what the run must return beside its diagnostics and final state:
    "amplitude" (the paper's amplitude, sqrt 2 times the roof's RMS over the window), "impacts" (the impact count),
    "peaks" (the certified peaks of the roof, every drift and every unit's stroke, and their RMS), "drifts" or
    "strokes" (the certified peaks of the storeys' drifts or of the units' strokes alone), "records" (each
    impact's time, unit, side, velocities and impulse, up to `record` of them), "samples" (every degree of freedom's
    displacement and velocity at `times`, a sorted array of instants).  Asking only for what is read lets the
    dispatch pick the fastest loop that measures it, and the scene loop certify only the peaks that are read: a
    peak not asked for is NaN, and so are the amplitude and the roof's RMS unless "amplitude" or "peaks" is asked.
    """
    asked = frozenset(measures)
    unknown = sorted(asked - set(MEASURES))
    if unknown:
        raise ParameterError(f"measures: {', '.join(map(repr, unknown))} unknown; allowed {', '.join(MEASURES)}")
    if (record and "records" not in asked) or (times is not None and "samples" not in asked):
        raise ParameterError("record and times come with the measures 'records' and 'samples'")
    for loop in LOOPS.values():
        if loop.fits(scene, asked):
            return loop.run(scene, asked, record, times)
    raise AssertionError("the scene loop runs every scene")  # unreachable: its fits is always true
