"""The engine's one entry point: impact.engine.run.simulate picks the loop from what the scene needs."""

from __future__ import annotations

import dataclasses
import inspect
import math
import re

import numpy as np
import pytest

from impact.engine import contact, layout, paper, paper_loop, scene_loop
from impact.engine import run as engine
from impact.engine.run import simulate_system
from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.params import ParameterError, Protocol, System
from impact.model.scene import (
    Contact,
    Damper,
    GroundMotion,
    Harmonic,
    Scene,
    State,
    paper_scene,
    paper_scene_from_system,
)

SHORT = Protocol(periods=60.0, average_from=30.0, start="left")
PAPER = dict(mu=0.01, beta=0.0048, e=0.25)


@pytest.mark.parametrize("system", [System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER),
                                    System.from_gap_ratio("pid", gap_ratio=1.0, rp=1.0, **PAPER)],
                         ids=["cid", "pid"])
def test_the_paper_case_runs_on_the_paper_loop_and_gives_its_numbers_to_the_bit(system):
    """Through the dispatch, the System's run is the paper loop's own, called on the System's numbers."""
    scene = paper_scene_from_system(system, 0.97, SHORT)
    result = engine.simulate(scene)
    assert result.loop == "paper" and simulate_system(system, 0.97, SHORT).loop == "paper"
    diag, z_out = np.zeros(layout.NDIAG), np.zeros(4)
    z0, code = paper.initial_state(system, SHORT.start)
    final = paper_loop.run(paper.param_vector(system, 0.97, SHORT), z0, code, paper.pid_data(system, 0.97), None,
                           np.zeros((0, layout.NREC)), diag, z_out)
    assert result.amplitude == paper.window_amplitude(diag, SHORT.t_window)[0]  # the same kernel: the same bits
    assert result.impacts == diag[layout.D_IMPACTS] > 0
    assert list(result.final_q) == [z_out[0], z_out[2]] and result.final_contacts[0].mode == ("free", "held")[
        final % 10]
    assert math.isnan(result.peak_roof_displacement)  # the paper loop certifies no peaks


def test_a_run_continues_from_its_final_state_on_either_loop():
    """A run of 2T from a State is the run of T continued by one of T from where it ended (its final State, the
    force's phase carried), to round-off on either loop: the force's phase is carried as a remainder, so the two
    halves see the same force to its last bits, not to the bit.  At r = 1, g = 1 the motion is drawn to an
    attractor, so round-off stays round-off (a phase moved by 1e-15 moves the end by 3e-13 here; at r = 0.97 the
    same start's transient amplifies it to 2e-6, and the continuation's difference, 2e-7, is inside that)."""
    system = System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER)
    half, whole = Protocol(periods=30.0, average_from=15.0), Protocol(periods=60.0, average_from=15.0)
    start = State.paper((0.0, 0.0, 0.4 * system.gap, 0.3))
    for measures in (("amplitude",), ("amplitude", "peaks")):
        scenes = [dataclasses.replace(paper_scene_from_system(system, 1.0, p), initial=start) for p in (half, whole)]
        first, both = (engine.simulate(s, measures) for s in scenes)
        phase = math.remainder(1.0 * half.t_end, 2.0 * math.pi)
        rest = dataclasses.replace(paper_scene_from_system(dataclasses.replace(system, phase=phase), 1.0, half),
                                   initial=first.final)
        second = engine.simulate(rest, measures)
        assert first.loop == second.loop == both.loop == ("paper" if len(measures) == 1 else "scene")
        assert first.impacts + second.impacts == both.impacts > 10
        np.testing.assert_allclose(second.final_q, both.final_q, rtol=0, atol=1e-11)
        assert second.final_contacts == both.final_contacts


def test_the_paper_loops_contact_code_decodes_to_the_state_it_encodes():
    """Every (mode, side, sigma) a run can start from or end in survives the integer the paper loop carries it in."""
    states = [(mode, side, sigma) for mode in (layout.MODE_FREE, layout.MODE_STUCK, layout.MODE_LOCKED,
                                                layout.MODE_FLOOR) for side in (-1, 0, 1) for sigma in (-1, 0, 1)]
    assert [paper_loop.decode_contact(paper_loop.contact_code(*s)) for s in states] == states
    assert len({paper_loop.contact_code(*s) for s in states}) == len(states)


def test_asking_for_peaks_moves_the_same_scene_to_the_scene_loop_and_the_physics_agrees():
    """At r = 1, g = 1 the steady state is an attractor (tests/test_scene.py's STABLE_CASES): a run forgets
    round-off, so the two exact loops agree to round-off over the paper's whole protocol."""
    system = System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER)
    scene = paper_scene_from_system(system, 1.0, Protocol(start="left"))
    fast = engine.simulate(scene)
    full = engine.simulate(scene, measures=("amplitude", "peaks"))
    assert (fast.loop, full.loop) == ("paper", "scene")
    assert full.amplitude == simulate_scene(scene).amplitude
    assert abs(full.amplitude - fast.amplitude) <= 1e-12 * fast.amplitude
    assert full.peak_roof_displacement >= fast.amplitude / math.sqrt(2.0)  # a peak is at least the RMS


@pytest.mark.parametrize("scene", [
    Scene(Building.paper(0.0048), (Damper("cid", 0.01, gap=1.0, e=0.25, units=2),), Harmonic(0.096, 0.97),
          duration=40.0),
    Scene(Building.paper(0.0048), (Damper("tmd", 0.01, tuning=0.98, damping=0.05),), Harmonic(0.096, 0.97),
          duration=40.0),
    Scene(Building.uniform(2, 1.0, 0.02), (Damper("cid", 0.05, gap=0.05, e=0.5),), Harmonic(0.1, 6.0),
          duration=10.0),
    Scene(Building.explicit([1.0], [4.0], zeta=0.0048), (Damper("cid", 0.01, gap=1.0, e=0.25),),
          Harmonic(0.096, 1.9), duration=40.0),
], ids=["two units", "tmd", "two storeys", "not model units"])
def test_every_other_scene_runs_on_the_scene_loop(scene):
    assert engine.as_paper_system(scene) is None
    assert engine.simulate(scene).loop == "scene"


def test_the_dispatch_table_tries_the_special_case_first_and_the_scene_loop_runs_everything():
    assert tuple(engine.LOOPS) == ("paper", "scene")
    assert engine.LOOPS["scene"].plan(Scene(Building.paper(0.01), (), Harmonic(0.1, 1.2), duration=10.0),
                                     frozenset(engine.MEASURES))


def test_samples_come_from_the_scene_loop_and_impact_records_from_either():
    system = System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER)
    scene = paper_scene_from_system(system, 0.97, SHORT)
    result = engine.simulate(scene, measures=("amplitude", "records", "samples"), record=5,
                             times=np.linspace(0.0, 1.0, 3))
    assert result.loop == "scene" and len(result.records["t"]) == 5 and result.samples["q"].shape == (3, 2)
    fast = engine.simulate(scene, measures=("amplitude", "records"), record=5)
    assert fast.loop == "paper" and set(fast.records) == set(result.records) and len(fast.records["t"]) == 5


def test_unknown_measures_and_stray_options_are_refused_by_name():
    scene = Scene(Building.paper(0.01), (), Harmonic(0.1, 1.2), duration=10.0)
    with pytest.raises(ParameterError, match="measures: 'stroke' unknown; allowed amplitude, impacts"):
        engine.simulate(scene, measures=("amplitude", "stroke"))
    with pytest.raises(ParameterError, match="record and times"):
        engine.simulate(scene, record=3)


def test_a_run_certifies_the_peaks_it_is_asked_for_to_round_off_and_no_others():
    """A run asked for the drifts or the strokes alone certifies those peaks as a run asked for every peak does
    (each monitor is searched on its own; the roof's row still gives the window its square when the amplitude is
    asked, and no window is integrated when neither it nor every peak is), reads NaN for the others, and moves,
    impacts and balances its energy as the full run does.  To round-off, not to the bit: a whole record step is
    taken by matrices where the monitors asked for are proved clear in it (engine/clear_step.py), so a run asked
    for fewer takes a few more such steps (176 against 174 here), each the same motion to round-off."""
    building = Building.uniform(3, 1.0, 0.02)
    t = np.arange(0.0, 6.0, 0.01)
    quake = GroundMotion(3.0 * np.sin(2.0 * np.pi * t) * np.exp(-0.3 * t), 0.01)
    scene = Scene(building, (Damper("cid", 0.02 * building.total_mass, gap=0.05, e=0.5, units=4),), quake)
    full = engine.simulate(scene, measures=("amplitude", "impacts", "peaks"))
    drifts = engine.simulate(scene, measures=("amplitude", "impacts", "drifts"))
    strokes = engine.simulate(scene, measures=("amplitude", "impacts", "strokes"))
    assert full.impacts > 10 and np.all(full.peak_strokes > 0.0)  # the units reach their walls
    np.testing.assert_allclose(drifts.peak_drifts, full.peak_drifts, rtol=1e-12)
    np.testing.assert_allclose(strokes.peak_strokes, full.peak_strokes, rtol=1e-12)
    scale = np.max(np.abs(full.final_q))
    for part in (drifts, strokes):
        np.testing.assert_allclose(part.final_q, full.final_q, rtol=0, atol=1e-12 * scale)
        assert part.impacts == full.impacts and part.amplitude == pytest.approx(full.amplitude, rel=1e-12)
        assert abs(part.diagnostics["energy_residual"]) <= 1e-12
        assert math.isnan(part.peak_roof_displacement) and math.isnan(part.peak_roof_acceleration)
    assert np.all(np.isnan(drifts.peak_strokes)) and np.all(np.isnan(strokes.peak_drifts))
    # the collapse stage's run: no amplitude, so no window; the same drifts, motion, impacts and energy
    bare = engine.simulate(scene, measures=("impacts", "drifts"))
    np.testing.assert_allclose(bare.peak_drifts, full.peak_drifts, rtol=1e-12)
    np.testing.assert_allclose(bare.final_q, full.final_q, rtol=0, atol=1e-12 * scale)
    assert bare.impacts == full.impacts and abs(bare.diagnostics["energy_residual"]) <= 1e-12
    assert math.isnan(bare.amplitude) and math.isnan(bare.rms_roof_displacement) and full.amplitude > 0.0
    assert math.isnan(engine.simulate(scene).peak_interstorey_drift)  # the default asks for no peak
    with pytest.raises(ParameterError, match="peaks: 'storeys' unknown; allowed roof, drifts, strokes, largest_drift"):
        simulate_scene(scene, peaks=("storeys",))


@pytest.mark.parametrize("kind", ["bare", "cid", "pid"])
def test_a_run_asked_for_the_largest_drift_certifies_the_largest_storeys_peak_on_fewer_searched_steps(kind):
    """The IDA's run (the roof's peaks, the largest drift, the strokes): its drift is the largest of the storeys'
    peaks that a run asked for every peak certifies, to round-off; each storey's reads NaN; and the storeys'
    shared running peak lets more record steps be taken whole (the point of sharing it: a storey below the largest
    no longer holds a step to a search), each the same motion to round-off, so impacts and roof peaks agree."""
    building = Building.uniform(5, 1.0, 0.02)
    t = np.arange(0.0, 8.0, 0.01)
    quake = GroundMotion(3.0 * np.sin(2.0 * np.pi * t) * np.exp(-0.3 * t) + np.sin(7.0 * t), 0.01)
    dampers = {"bare": (), "cid": (Damper("cid", 0.02 * building.total_mass, gap=0.08, e=0.5),),
               "pid": (Damper("pid", 0.02 * building.total_mass, gap=0.1, e=0.5, tuning=1.0, damping=0.02),)}[kind]
    scene = Scene(building, dampers, quake)
    full = engine.simulate(scene, measures=("impacts", "peaks"))
    ida = engine.simulate(scene, measures=("impacts", "roof", "largest_drift", "strokes"))
    assert ida.peak_interstorey_drift == pytest.approx(np.max(full.peak_drifts), rel=1e-12)
    assert np.all(np.isnan(ida.peak_drifts)) and np.all(np.isnan(ida.peak_roundoff[2:7]))
    assert (ida.peak_roof_displacement, ida.peak_roof_acceleration) == pytest.approx(
        (full.peak_roof_displacement, full.peak_roof_acceleration), rel=1e-12)
    np.testing.assert_allclose(ida.peak_strokes, full.peak_strokes, rtol=1e-12)
    assert ida.impacts == full.impacts and (kind == "bare" or full.impacts > 0)
    assert abs(ida.diagnostics["energy_residual"]) <= 1e-12 and math.isnan(ida.rms_roof_displacement)
    assert ida.diagnostics["clear_steps"] > full.diagnostics["clear_steps"]
    with pytest.raises(ParameterError, match="allowed roof, drifts, strokes, largest_drift"):
        simulate_scene(scene, peaks=("largest_stroke",))


def test_the_paper_loop_defines_no_index_of_its_own_and_reads_the_engines_one_layout():
    """Every parameter, diagnostic, record and mode index the paper loop reads is layout.py's."""
    own = [name for name in vars(paper_loop) if re.fullmatch(r"(P|D|R|MODE)_[A-Z0-9_]+|N(PAR|DIAG|REC)\w*", name)]
    assert own == [] and paper_loop.L is layout
    read = set(re.findall(r"\bL\.([A-Z][A-Z0-9_]*)", inspect.getsource(paper_loop)))
    assert {"P_MU", "P_GAP", "P_PERIOD", "P_VSTICK", "D_X2WIN", "D_CAP", "MODE_STUCK"} <= read
    assert read <= set(vars(layout))
    # its impact records are the scene loop's, written by the one writer both loops call
    assert {"R_X", "R_IMPULSE"} <= set(re.findall(r"\bL\.(R_[A-Z0-9_]*)", inspect.getsource(contact.record_impact)))


# a write to a unit's contact mode or slide sign: an element of mode or sigma assigned (not compared)
_CONTACT_WRITE = re.compile(r"\b(?:mode|sigma)\[[^\]]*\]\s*=(?!=)")
# where a run's contact state is set up, before any event: what the run was given, not a transition
_START_STATE = {"_initial_contact", "_initial_units"}
_TRANSITIONS = ("meet_wall", "leave_wall", "rebound", "hold", "start_slide", "rest_on_floor", "slip", "slide_with")


def _own_functions(module):
    """{name: source} of the functions a module defines (numba's dispatchers read through to their Python)."""
    found = {}
    for name, value in vars(module).items():
        fn = getattr(value, "py_func", value)
        if inspect.isfunction(fn) and fn.__module__ == module.__name__:
            found[name] = inspect.getsource(fn)
    return found


def test_both_loops_change_a_contact_only_through_the_one_state_machine():
    """Every change of a unit's contact mode or slide sign after a run starts is one of contact.py's transitions,
    which both loops call: neither loop writes a mode or a slide sign of its own (the wall's side and the escapes
    may be set beside a transition, where a loop alone knows them)."""
    writers = [f"{module.__name__}.{name}" for module in (paper_loop, scene_loop)
               for name, source in _own_functions(module).items()
               if name not in _START_STATE and _CONTACT_WRITE.search(source)]
    assert writers == []
    assert all(_CONTACT_WRITE.search(_own_functions(contact)[name]) for name in _TRANSITIONS)
    for module in (paper_loop, scene_loop):
        called = {name for name in _TRANSITIONS if re.search(rf"\b{name}\((?:c|st), ", inspect.getsource(module))}
        assert called, module.__name__
    both = {name for name in _TRANSITIONS
            if all(re.search(rf"\b{name}\((?:c|st), ", inspect.getsource(m)) for m in (paper_loop, scene_loop))}
    assert both == {"meet_wall", "leave_wall", "rebound", "hold", "start_slide", "rest_on_floor", "slide_with"}  # slip: units jolted


def test_a_mass_touching_its_wall_while_leaving_it_slowly_rests_there_on_both_loops():
    """The paper's damper mass starts at its right wall, leaving it at 1e-12 (below the sticking speed), while the
    force drives the structure away from it (x'' = -F0 < 0 at t = 0, so the wall pushes the mass along): the
    touch is a rest on the wall, which holds it, on both loops alike, and no impact is counted (the paper loop once
    let such a mass leave and counted the strike that followed)."""
    scene = paper_scene("cid", mu=0.01, beta=0.0048, e=0.5, gap=1.0, r=1.0, periods=0.1, average_from=0.05,
                        phase=-0.5 * math.pi,
                        initial=State.paper((0.0, 0.0, 0.5, -1e-12)))
    fast = engine.simulate(scene, ("amplitude", "impacts"))
    full = engine.simulate(scene, ("amplitude", "impacts", "peaks"))
    assert (fast.loop, full.loop) == ("paper", "scene")
    for res in (fast, full):
        assert res.impacts == 0 and res.diagnostics["sticking_episodes"] == 1, res.loop
        assert res.final_contacts[0].mode == "held" and res.final_contacts[0].side == 1, res.loop
    np.testing.assert_allclose(fast.final_q, full.final_q, rtol=1e-12)


def test_both_loops_report_the_same_diagnostics_and_record_the_same_impacts():
    """At r = 1, g = 1 the steady state is an attractor (as above), so the two loops' records of the same run
    agree column by column, and each impact keeps the momentum of structure and damper (M = 1, m = mu)."""
    system = System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER)
    proto = Protocol(periods=60.0, average_from=30.0, start="left")
    fast = simulate_system(system, 1.0, proto, record=200)
    full = simulate_scene(paper_scene_from_system(system, 1.0, proto), record=200)
    assert set(fast.diagnostics) == set(full.diagnostics)
    assert set(fast.records) == set(full.records)
    rec, mu = fast.records, system.mu
    assert len(rec["t"]) > 60 and np.all(rec["unit"] == 0)
    np.testing.assert_allclose(rec["v_plus"] + mu * rec["w_plus"], rec["v_minus"] + mu * rec["w_minus"],
                               rtol=0, atol=1e-14)
    np.testing.assert_allclose(rec["impulse"], rec["side"] * (rec["v_plus"] - rec["v_minus"]), rtol=1e-12)
    # Newton's law with the reduced mass: the impulse is mu (1 + e) / (1 + mu) of the approach speed
    approach = rec["side"] * (rec["w_minus"] - rec["v_minus"])
    np.testing.assert_allclose(rec["impulse"], mu * (1.0 + system.e) / (1.0 + mu) * approach, rtol=1e-12)
    assert np.all(rec["impulse"] > 0.0)
    for column in ("t", "side", "x", "v_minus", "w_minus", "v_plus", "w_plus", "stuck", "impulse"):
        np.testing.assert_allclose(full.records[column], rec[column], rtol=1e-9, atol=1e-12, err_msg=column)


def _left_start(scene: Scene) -> State:
    """The State of Scene(start="left"): every floor at rest, every unit at rest on its left wall."""
    n, units = scene.building.storeys, scene.unit_list()
    q = [0.0] * n + [-0.5 * d.gap for _, d in units]
    return State(q, [0.0] * len(q), [Contact("held", -1)] * len(units))


@pytest.mark.parametrize("measures", [("amplitude", "impacts"), ("amplitude", "peaks")], ids=["paper", "scene"])
def test_a_state_at_rest_on_the_walls_is_the_protocols_wall_start_to_the_bit(measures):
    system = System.from_gap_ratio("cid", gap_ratio=1.0, **PAPER)
    scene = paper_scene_from_system(system, 0.97, SHORT)  # SHORT starts on the left wall
    given = dataclasses.replace(scene, start="centre", initial=_left_start(scene))
    a, b = engine.simulate(scene, measures), engine.simulate(given, measures)
    assert a.loop == b.loop and a.amplitude == b.amplitude and a.impacts == b.impacts > 0
    assert list(a.final_q) == list(b.final_q) and a.final_contacts == b.final_contacts


def test_a_building_started_moving_balances_its_energy_from_the_state_it_was_given():
    """Two storeys and two CID units started with velocities and off-centre strokes: the run's initial energy is
    the given state's (kinetic plus strain), and the balance closes to 1e-9 across the impacts that follow."""
    building = Building.uniform(2, 1.0, 0.02)
    damper = Damper("cid", 0.02 * building.total_mass, gap=0.02, e=0.5, units=2)
    state = State((0.01, 0.02, 0.025, 0.015), (0.1, 0.2, -0.3, 0.4), (Contact(), Contact()))
    scene = Scene(building, (damper,), Harmonic(0.01, 1.0), duration=5.0, initial=state)
    res = engine.simulate(scene, ("peaks",))
    m = np.concatenate([building.masses, [damper.mass / 2] * 2])  # the damper's mass shared by its units

    def energy(q, v):
        q = np.asarray(q)
        return 0.5 * float(np.sum(m * np.square(v))) + 0.5 * float(q[:2] @ building.stiffness @ q[:2])

    d = res.diagnostics
    assert res.loop == "scene" and res.impacts > 5
    losses = d["viscous_dissipation"] + d["impact_losses"]
    # what the run started with, by its own balance: what it ended with and lost, less what the force put in
    started = energy(res.final_q, res.final_v) + losses - d["work_input"]
    assert started == pytest.approx(energy(state.q, state.v), rel=1e-9)
    assert abs(d["energy_residual"]) <= 1e-9 and losses > 0.1 * started


@pytest.mark.parametrize("initial, field", [
    (State((0.0, 0.0), (0.0, 0.0)), "contacts"),
    (State((0.0,), (0.0,), (Contact(),)), "degrees of freedom"),
    (State((0.0, 0.6), (0.0, 0.0), (Contact(),)), "beyond its walls"),
])
def test_a_state_that_does_not_fit_the_scene_is_refused_by_name(initial, field):
    with pytest.raises(ParameterError, match=field):
        Scene(Building.paper(0.0048), (Damper("cid", 0.01, gap=1.0, e=0.25),), Harmonic(0.096, 0.97), duration=40.0,
              initial=initial)


def test_a_contact_out_of_range_is_refused_by_name():
    with pytest.raises(ParameterError, match="mode"):
        Contact("stuck")
    with pytest.raises(ParameterError, match="side"):
        Contact("held")
    with pytest.raises(ParameterError, match="slide"):
        Contact("free", slide=2)


def test_a_free_decay_is_a_scene_with_no_force_on_either_loop():
    """Released from x0 with the damper mass beside it and no force: the bare structure's closed form before the
    first impact, and the paper loop's dense output (its samples rebuilt between impacts) equal to the scene
    loop's dense output to round-off across the impacts that follow."""
    system = System.from_gap_ratio("pid", gap_ratio=1.0, rp=1.0, **PAPER)
    x0 = 2.0
    scene = paper_scene_from_system(dataclasses.replace(system, force_ratio=0.0), 1.0,
                                    Protocol(periods=8.0, average_from=0.0), initial=State.paper((x0, 0, x0, 0)))
    times = np.linspace(0.0, scene.t_end, 801)
    fast = engine.simulate(scene, ("samples", "records"), record=100, times=times)
    full = engine.simulate(scene, ("samples", "records", "peaks"), record=100, times=times)
    assert (fast.loop, full.loop) == ("paper", "scene") and fast.impacts == full.impacts > 2
    assert math.isnan(fast.diagnostics["energy_residual"]) and abs(full.diagnostics["energy_residual"]) <= 1e-9
    np.testing.assert_allclose(fast.samples["q"], full.samples["q"], rtol=0, atol=1e-10 * x0)
    np.testing.assert_allclose(fast.records["t"], full.records["t"], rtol=1e-10)
    # before the first impact the structure is the damped oscillator and the pendulum hangs with it (no force)
    before = times < fast.records["t"][0]
    b, wd = system.beta, math.sqrt(1.0 - system.beta ** 2)
    bare = x0 * np.exp(-b * times) * (np.cos(wd * times) + b / wd * np.sin(wd * times))
    x = fast.samples["q"][:, 0]
    assert np.max(np.abs(x[before] - bare[before])) > 0  # the pendulum's reaction is there, small
    np.testing.assert_allclose(x[before], bare[before], rtol=0, atol=0.05 * x0)


def test_the_paper_loops_dense_output_refuses_friction_by_name():
    system = System.from_gap_ratio("cid", gap_ratio=1.0, nu=0.05, **PAPER)
    scene = paper_scene_from_system(system, 1.0, SHORT)
    with pytest.raises(ParameterError, match="friction"):
        engine.simulate(scene, ("samples",), times=np.array([0.0, 1.0]))
