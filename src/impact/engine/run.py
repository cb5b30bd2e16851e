"""One entry point to the engine: ``simulate(scene, measures=...)`` picks the loop that runs it.

    result = simulate(scene)                                  # amplitude, impacts, diagnostics
    result = simulate(scene, measures=("amplitude", "peaks"))  # and the certified peaks
    run = simulate_system(system, r, protocol)                # the paper's system under its protocol
    runs = sweep(system, r_values, protocol, mode="continuation_up")

``simulate_system`` and ``sweep`` speak the paper's language (a :class:`~impact.model.params.System` in model
units, a frequency ratio, the response :class:`~impact.model.params.Protocol`): each run is a Scene that
``simulate`` dispatches, so the paper's study takes the same way in as every scene.

:data:`LOOPS` is the dispatch table, tried in order: the first loop that can run the scene and
measure what is asked runs it.  The paper loop (:mod:`.paper_loop`) runs the paper's one-storey,
one-unit harmonic case in model units, several times faster (``benchmarks/bench_loops.py``);
the scene loop (:mod:`.scene_loop`) runs every scene.  Both return a :class:`~.scenes.SceneResult`;
what a loop does not measure is NaN there, and ``result.loop`` names the loop that ran.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from impact.engine import layout as L
from impact.engine import paper
from impact.engine import paper_loop as K
from impact.engine.contact import free_vibration_stick
from impact.engine.diagnostics import ENERGY_TERMS, read_diagnostics
from impact.engine.scenes import (
    LARGEST_OF,
    MODE_CODES,
    PEAK_GROUPS,
    EndsInState,
    SceneResult,
    contacts_of,
    simulate_scene,
)
from impact.model.params import ParameterError, Protocol, System, ipc_class, ipc_label
from impact.model.scene import Harmonic, Scene, State, paper_scene_from_system

#: what a run can measure: the window's amplitude (sqrt 2 RMS of the roof), the impacts and diagnostics
#: with the final state, the certified peaks of every monitor (roof, drifts, strokes) with the roof's RMS, or of
#: one group of monitors alone (scenes.PEAK_GROUPS) or the largest of one (scenes.LARGEST_OF), impact records and
#: the state at requested times
MEASURES = ("amplitude", "impacts", "peaks", *PEAK_GROUPS, *LARGEST_OF, "records", "samples")
DEFAULT_MEASURES = ("amplitude", "impacts")
PAPER_MEASURES = frozenset(("amplitude", "impacts", "records"))
#: what the paper loop's dense output measures (paper.dense_samples): the state at the sample times, the impacts and
#: their records.  It runs the loop in chunks between the samples, so it integrates no window: no amplitude
PAPER_SAMPLED_MEASURES = frozenset(("samples", "impacts", "records"))


@dataclass(frozen=True)
class Loop:
    """A loop of the engine: its plan for a scene with these measures (None when it cannot run it; what the run
    needs of the scene otherwise, worked out once), and the run, given the plan."""

    plan: Callable[[Scene, frozenset], object]
    run: Callable[..., SceneResult]


def as_paper_system(scene: Scene) -> System | None:
    """The scene as the paper loop's System, when it is the paper's case in model units; None otherwise.

    The paper's case: one storey of mass 1 and stiffness 1 (omega = 1, time in radians of the structure),
    one CID or undamped PID unit, a harmonic force on that storey, the unit starting at rest in the centre
    or on a wall, or from a given State (Scene.initial).  Every number is taken as the scene holds it, so a scene built by
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
    return _system(d.kind, d.mass, b.zeta, d.e, d.gap, d.tuning if d.kind_spec.spring else 0.0, load.amplitude,
                   load.phase, d.nu)


@functools.lru_cache(maxsize=256)
def _system(kind: str, mu: float, beta: float, e: float, gap: float, rp: float, force_ratio: float, phase: float,
            nu: float) -> System:
    """The System of these numbers, checked once: a sweep from rest runs one System at every frequency."""
    return System(kind, mu=mu, beta=beta, e=e, gap=gap, rp=rp, force_ratio=force_ratio, phase=phase, nu=nu)


def _paper_plan(scene: Scene, measures: frozenset) -> System | None:
    """The scene's System, when the paper loop measures what is asked and the scene is the paper's case."""
    fits = measures <= PAPER_MEASURES or ("samples" in measures and measures <= PAPER_SAMPLED_MEASURES)
    return as_paper_system(scene) if fits else None


def _paper_start(system: System, scene: Scene) -> tuple[np.ndarray, int]:
    """The paper loop's (x, x', y, y') and contact code where the scene starts."""
    if scene.initial is None:
        return paper.initial_state(system, scene.start)
    (x, y), (xd, yd), (c,) = scene.initial.q, scene.initial.v, scene.initial.contacts
    return np.array([x, xd, y, yd]), K.contact_code(MODE_CODES[c.mode], c.side, c.slide)


def _paper_result(scene: Scene, diagnostics: dict, z: np.ndarray, final_code: int, **measured) -> SceneResult:
    """A paper loop's run as a SceneResult: what it measured given, the scene loop's peaks NaN (it has none), its
    final state from (x, x', y, y') and its contact code (paper_loop.contact_code)."""
    nan = math.nan
    return SceneResult(
        scene=scene, peak_roof_displacement=nan, peak_roof_displacement_time=nan, peak_roof_acceleration=nan,
        peak_interstorey_drift=nan, peak_drifts=np.full(1, nan), peak_strokes=np.full(1, nan),
        diagnostics=diagnostics, final_q=z[[0, 2]].copy(), final_v=z[[1, 3]].copy(), loop="paper",
        final_contacts=contacts_of([K.decode_contact(int(final_code))]), **measured)


def _run_paper(scene: Scene, system: System, measures: frozenset, record: int, times) -> SceneResult:
    r = scene.load.omega
    paper.check_resonance(system, r)
    z0, code = _paper_start(system, scene)
    p = paper.run_parameters(system, r, scene.t_end, scene.t_window, scene.max_events_per_period,
                             max_events=scene.event_budget)
    if not system.force_ratio:
        p[L.P_VSTICK] = free_vibration_stick(z0[[0, 2]], z0[[1, 3]], 1.0)  # the paper's units: omega1 = 1
    if "samples" in measures:
        return _sampled_paper_run(scene, system, p, z0, code, record, times)
    fric = np.array([system.nu * scene.gravity]) if system.nu > 0.0 else None
    paper.ensure_compiled(system.kind, fric is not None)
    diag = np.zeros(L.NDIAG)
    z_out = np.zeros(4)
    rec = np.zeros((int(record), L.NREC))
    final = K.run(p, z0, int(code), paper.pid_data(system, r), fric, rec, diag, z_out)
    amp, span, complete = paper.window_amplitude(diag, scene.t_window)
    return _paper_result(scene, read_diagnostics(diag), z_out, final, impacts=int(diag[L.D_IMPACTS]),
                         rms_roof_displacement=math.sqrt(diag[L.D_X2WIN] / span) if complete else math.nan,
                         records=_records(rec, diag), amplitude=amp, window_span=float(span))


def _sampled_paper_run(scene: Scene, system: System, p: np.ndarray, z0: np.ndarray, code: int, record: int,
                       times) -> SceneResult:
    """The paper loop's dense output: the state at the sorted times, run in chunks of about one forcing period's
    samples (each chunk one call of the loop, its samples rebuilt from its impacts' post-impact states).  Its
    diagnostics count the impacts and say whether the event guard stopped a call; its energy terms are NaN, since
    each call balances its own."""
    if system.nu > 0.0:
        raise ParameterError("the paper loop's dense output has no friction: ask the scene loop (measures 'peaks')")
    times = np.asarray(times, dtype=float)
    r = scene.load.omega
    spacing = (times[-1] - times[0]) / (len(times) - 1) if len(times) > 1 else 2.0 * math.pi / r
    chunk = max(1, int(round(2.0 * math.pi / (r * spacing))))
    paper.ensure_sampler_compiled()
    zs, kept, impacts, capped, final, z = paper.dense_samples(p, paper.pid_data(system, r), z0, code, times, chunk,
                                                              record)
    diag = np.zeros(L.NDIAG)
    diag[L.D_IMPACTS] = impacts
    diag[L.D_CAP] = 1.0 if capped else 0.0
    diagnostics = read_diagnostics(diag)
    diagnostics.update({key: math.nan for key in ENERGY_TERMS})
    return _paper_result(scene, diagnostics, z, final, impacts=impacts, rms_roof_displacement=math.nan,
                         records={c: kept[:, i].copy() for i, c in enumerate(L.RECORD_COLUMNS)},
                         samples={"t": times, "q": zs[:, [0, 2]], "v": zs[:, [1, 3]]})


def _records(rec: np.ndarray, diag: np.ndarray) -> dict | None:
    """The impact records a loop wrote (layout.RECORD_COLUMNS), or None when none were asked."""
    if not rec.shape[0]:
        return None
    n = int(diag[L.D_NREC])
    return {c: rec[:n, i].copy() for i, c in enumerate(L.RECORD_COLUMNS)}


def _run_scene(scene: Scene, plan, measures: frozenset, record: int, times) -> SceneResult:
    return simulate_scene(scene, record=record, times=times, peaks=peak_groups(measures), window=has_window(measures))


def has_window(measures: frozenset) -> bool:
    """Whether the measures read the window's square of the roof: the amplitude, or the roof's RMS that "peaks"
    reports with its peaks.  A run asked for neither (the collapse stage's: impacts and drifts) integrates no
    window, and its amplitude and RMS are NaN."""
    return "amplitude" in measures or "peaks" in measures


def peak_groups(measures: frozenset) -> tuple:
    """The monitors' groups (scenes.PEAK_GROUPS) whose peaks the measures ask the scene loop to certify: every
    group for "peaks", else those named ("roof", "drifts", "strokes"), and those asked for their largest alone
    (scenes.LARGEST_OF); a group not asked costs nothing and reads NaN."""
    if "peaks" in measures:
        return PEAK_GROUPS
    return tuple(g for g in (*PEAK_GROUPS, *LARGEST_OF) if g in measures)


#: the loops, tried in order (the fast special case first)
LOOPS = {"paper": Loop(_paper_plan, _run_paper), "scene": Loop(lambda scene, measures: True, _run_scene)}


def simulate(scene: Scene, measures=DEFAULT_MEASURES, *, record: int = 0, times=None) -> SceneResult:
    """Run a scene on the engine's first loop (:data:`LOOPS`) that measures what is asked.

    measures: names from :data:`MEASURES`, what the run must return beside its diagnostics and final state:
    "amplitude" (the paper's amplitude, sqrt 2 times the roof's RMS over the window), "impacts" (the impact count),
    "peaks" (the certified peaks of the roof, every drift and every unit's stroke, and the roof's RMS), "roof",
    "drifts" or "strokes" (the certified peaks of the roof's displacement and acceleration, of the storeys' drifts
    or of the units' strokes alone, without the RMS), "largest_drift" (the largest of the storeys' drifts alone,
    certified as the peak of the group's largest: each storey's reads NaN), "records" (each
    impact's time, unit, side, velocities and impulse, up to `record` of them), "samples" (every degree of freedom's
    displacement and velocity at `times`, a sorted array of instants, and, from the scene loop, each displacement's
    round-off, "q_roundoff").  Asking only for what is read lets the
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
        plan = loop.plan(scene, asked)
        if plan is not None:
            return loop.run(scene, plan, asked, record, times)
    raise AssertionError("the scene loop runs every scene")  # unreachable: its plan is always True


# ----------------------------------------------------------------------------
# the paper's system under its response protocol: each run a Scene, dispatched as every scene
# ----------------------------------------------------------------------------


@dataclass
class RunResult(EndsInState):
    """One run under the response protocol (model units): the amplitude over the window, its ratio to the bare
    structure's resonant amplitude, the impacts per forcing cycle (aipc) and their class, and where it ended."""

    r: float
    amplitude: float
    amplitude_ratio: float
    aipc: float
    ipc_class: int
    diagnostics: dict
    final_q: np.ndarray = field(repr=False)
    final_v: np.ndarray = field(repr=False)
    final_contacts: tuple = ()
    records: dict | None = field(default=None, repr=False)
    loop: str = "paper"

    @property
    def final_state(self) -> np.ndarray:
        """(x, x', y, y') at the run's end: the structure's and the damper mass's displacement and velocity."""
        (x, y), (xd, yd) = self.final_q, self.final_v
        return np.array([x, xd, y, yd])

    def as_json(self) -> dict:
        return {"r": self.r, "amplitude": self.amplitude, "amplitude_ratio": self.amplitude_ratio, "aipc": self.aipc,
                "ipc_class": ipc_label(self.aipc), "diagnostics": self.diagnostics}


def simulate_system(system: System, r: float, protocol: Protocol = Protocol(), *, record: int = 0,
                    initial: State | None = None) -> RunResult:
    """One run of the paper's system at frequency ratio r under the protocol, through :func:`simulate`.

    record: keep up to this many impact records (layout.RECORD_COLUMNS).  initial: the State to start from
    (a previous run's ``final``, or a closed-form orbit's point) instead of the protocol's rest state.
    """
    scene = paper_scene_from_system(system, r, protocol, initial=initial)
    res = simulate(scene, DEFAULT_MEASURES + (("records",) if record else ()), record=record)
    complete = math.isfinite(res.amplitude)
    cycles = res.window_span * r / (2.0 * math.pi)
    aipc = res.diagnostics["impacts_in_window"] / cycles if complete else math.nan
    amax = system.a_max
    return RunResult(r=float(r), amplitude=res.amplitude,
                     amplitude_ratio=res.amplitude / amax if 0.0 < amax < math.inf else math.nan, aipc=aipc,
                     ipc_class=ipc_class(aipc), diagnostics=res.diagnostics, final_q=res.final_q,
                     final_v=res.final_v, final_contacts=res.final_contacts, records=res.records, loop=res.loop)


@dataclass
class SweepResult:
    """A frequency sweep under the protocol: per-r results and the paper's x_max, X_m."""

    r: np.ndarray
    runs: list

    def column(self, name: str) -> np.ndarray:
        if name in ("amplitude", "amplitude_ratio", "aipc", "ipc_class"):
            return np.array([getattr(run, name) for run in self.runs])
        return np.array([run.diagnostics[name] for run in self.runs])

    @property
    def x_max(self) -> float:
        amp = self.column("amplitude")
        return float(np.max(amp)) if np.all(np.isfinite(amp)) else math.nan

    @property
    def r_at_max(self) -> float:
        amp = self.column("amplitude")
        return float(self.r[int(np.nanargmax(amp))]) if np.any(np.isfinite(amp)) else math.nan


SWEEP_MODES = ("from_rest", "continuation_up", "continuation_down")


def _progress(values, show: bool):
    """values, with a progress bar on stderr when asked and stderr is a terminal (tqdm: silent otherwise)."""
    if not show:
        return values
    from tqdm import tqdm

    return tqdm(values, desc="frequencies", unit="run", leave=False, disable=None)


def sweep(system: System, r_values, protocol: Protocol = Protocol(), mode: str = "from_rest",
          initial: State | None = None, progress: bool = False) -> SweepResult:
    """Frequency sweep under the protocol.

    from_rest: every frequency starts afresh from the protocol's start (or from `initial` when given: one
    initial condition for every frequency).  continuation_up / _down: frequencies in increasing / decreasing
    order, each starting from the final state of the previous one, as a slow physical sweep would; the force
    stays continuous (its phase carries over).  Each frequency still runs the protocol's periods and window,
    so the first average_from periods settle the new frequency.  Results are in the order of r_values either
    way.  progress: a progress bar on stderr when it is a terminal (tqdm).
    """
    if mode not in SWEEP_MODES:
        raise ValueError(f"sweep mode {mode!r} is not one of {', '.join(SWEEP_MODES)}")
    r_values = np.asarray(r_values, dtype=float)
    if mode == "from_rest":
        runs = [simulate_system(system, float(r), protocol, initial=initial) for r in _progress(r_values, progress)]
        return SweepResult(r=r_values, runs=runs)
    order = np.argsort(r_values, kind="stable")
    if mode == "continuation_down":
        order = order[::-1]
    runs = [None] * len(r_values)
    current, state = system, initial
    for i in _progress(order, progress):
        r = float(r_values[i])
        run = simulate_system(current, r, protocol, initial=state)
        runs[i] = run
        state = run.final
        # the force phase at the end of this run is the next run's phase at t = 0
        end_phase = math.remainder(r * protocol.t_end + current.phase, 2.0 * math.pi)
        current = dataclasses.replace(current, phase=end_phase)
    return SweepResult(r=r_values, runs=runs)
