"""Whole record steps by matrices (impact.engine.clear_step): the same motion, energy and certified peaks as the
segment's modal rows, to round-off, with every step they take proved clear of walls and of the peaks."""

from __future__ import annotations

from dataclasses import replace
from itertools import combinations

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import expm

from impact.closed_form.propagator import first_order_hold
from impact.engine import layout as L
from impact.engine.clear_step import MOST_PATTERNS, MOST_YIELDING, _row_ends, clear_step_tables, pattern
from impact.engine.scenes import _scene_arrays, run_arrays, simulate_scene
from impact.model.building import Building
from impact.model.records import load_record
from impact.model.scene import Damper, ForceRecord, GroundMotion, Scene


@pytest.fixture(scope="module")
def three_storey():
    return Building.uniform(3, 1.0, 0.02)


@pytest.fixture(scope="module")
def el_centro():
    return GroundMotion.from_record(load_record("elcentro"), pga_g=0.35)


def _damped_scenes(building, motion):
    """A damper of several units and a TMD on one building (units that fly and units that swing), and a PID."""
    m = 0.02 * building.total_mass
    return {"cid in 4 units and a tmd": Scene(building, (Damper("cid", m, gap=0.05, e=0.5, units=4),
                                                        Damper("tmd", m, tuning=0.98, damping=0.06)), motion),
            "pid": Scene(building, (Damper("pid", m, gap=0.2, e=0.5, tuning=1.0),), motion)}


def _yielding_scenes(building, motion):
    """The same building yielding at 1 cm with 5 % hardening, bare; and with P-delta (3.5 m storeys) and a CID,
    stopping at a 10 % drift ratio: elastic branches between yield and unloading events."""
    soft = building.yielding(0.01, 0.05)
    heavy = building.yielding(0.01, 0.05, storey_height=np.full(building.storeys, 3.5), p_delta=True)
    cid = Damper("cid", 0.02 * building.total_mass, gap=0.05, e=0.5)
    return {"yielding, bare": Scene(soft, (), motion),
            "yielding, p-delta and a cid": Scene(heavy, (cid,), motion, collapse_drift_ratio=0.1)}


def test_the_flow_is_the_first_order_hold(three_storey, el_centro):
    """The tables' flow over (q, q', f(0), f') is the propagator's x_{k+1} = A x_k + B0 a_k + B1 a_{k+1}: with
    f' = (a_{k+1} - a_k) / dt, its f(0) column is B0 + B1 and its f' column B1 dt."""
    clear = pattern(_scene_arrays(Scene(three_storey, (), el_centro))["clear"], 0)
    a, b0, b1 = first_order_hold(three_storey, el_centro.dt)
    n = 2 * three_storey.storeys
    scale = np.max(np.abs(a))
    assert np.max(np.abs(clear.flow[:, :n] - a)) <= 1e-13 * scale
    assert np.max(np.abs(clear.flow[:, n] - (b0 + b1))) <= 1e-13 * np.max(np.abs(b0))
    assert np.max(np.abs(clear.flow[:, n + 1] - b1 * el_centro.dt)) <= 1e-13 * np.max(np.abs(b1 * el_centro.dt))


def test_the_quadratic_forms_are_the_step_integrals(three_storey, el_centro):
    """Work, dissipation and the roof's square over a step, as forms of the step's start, against quadrature of
    the same integrands along the motion (scipy.integrate.quad of u(t) = exp(F t) u0, F built here from the
    scene's arrays), on a scene with flying and swinging units; and the flow is exp(F dt)."""
    arrays = _scene_arrays(_damped_scenes(three_storey, el_centro)["cid in 4 units and a tmd"])
    clear, load_vec = pattern(arrays["clear"], 0), arrays["model"].load_vec
    gen, damping = _true_generator(arrays)
    n = len(load_vec)
    rng = np.random.default_rng(20261130)
    u0 = np.concatenate([rng.normal(0, 0.05, n), rng.normal(0, 0.3, n), [2.0, -40.0]])
    dt = el_centro.dt

    def integral(integrand):
        return quad(lambda t: integrand(expm(gen * t) @ u0), 0.0, dt, epsabs=0, epsrel=1e-13)[0]

    work = integral(lambda u: u[2 * n] * (load_vec @ u[n : 2 * n]))
    visc = integral(lambda u: u[n : 2 * n] @ damping @ u[n : 2 * n])
    square = integral(lambda u: u[2] ** 2)
    assert u0 @ clear.work @ u0 == pytest.approx(work, rel=1e-11)
    assert u0 @ clear.visc @ u0 == pytest.approx(visc, rel=1e-11)
    assert u0 @ clear.square @ u0 == pytest.approx(square, rel=1e-11)
    exact = expm(gen * dt)[: 2 * n]
    assert np.max(np.abs(clear.flow - exact)) <= 1e-13 * np.max(np.abs(exact))


def _true_generator(arrays, yielding=()):
    """The scene's generator over (q, q', f, f', p) with every unit free, the storeys in `yielding` on a yielding
    branch (stiffness b k) and the others elastic (p: the storeys' plastic offsets, constant there; a yielding
    storey's -s d_y, its element's constant force over its pull), and its damping matrix, built here from the
    scene's own arrays."""
    model, springs, yld = arrays["model"], arrays["springs"], arrays["yld"]
    nf = len(model.building.mass)
    n = len(model.load_vec)
    mass = np.concatenate([model.building.mass, model.units.mass])
    k = np.zeros((n, n))
    c = np.zeros((n, n))
    c[:nf, :nf] = model.building.damping
    joint = np.array([[1.0, -1.0], [-1.0, 1.0]])
    storeys = 0 if yld is None else nf
    pulls = np.zeros((n, storeys))
    stiff = model.building.stiffness
    storey_k = [stiff[i, i] + (stiff[i + 1, i] if i < nf - 1 else 0.0) for i in range(nf)]  # K[i+1, i] = -k_(i+1)
    for i in range(nf):
        k_i = storey_k[i]
        if yld is not None:
            pulls[i, i] = (1.0 - yld.hardening[i]) * yld.stiffness[i]
            if i > 0:
                pulls[i - 1, i] = -pulls[i, i]
            k_i -= yld.geometric[i] + (pulls[i, i] if i in yielding else 0.0)
        floors = [i - 1, i] if i > 0 else [i]
        k[np.ix_(floors, floors)] += k_i * (joint if i > 0 else 1.0)
    for j, f in enumerate(model.units.floor):
        if springs is not None:
            for matrix, value in ((k, springs.stiffness[j]), (c, springs.damping[j])):
                matrix[np.ix_([f, nf + j], [f, nf + j])] += value * joint
    gen = np.zeros((2 * n + 2 + storeys,) * 2)
    gen[:n, n : 2 * n] = np.eye(n)
    gen[n : 2 * n, :n] = -k / mass[:, None]
    gen[n : 2 * n, n : 2 * n] = -c / mass[:, None]
    gen[n : 2 * n, 2 * n] = model.load_vec / mass
    gen[2 * n, 2 * n + 1] = 1.0
    gen[n : 2 * n, 2 * n + 2 :] = pulls / mass[:, None]
    return gen, c


@pytest.mark.parametrize("label", ["cid in 4 units and a tmd", "pid", "yielding, p-delta and a cid"])
def test_the_bounds_hold_over_a_step(three_storey, el_centro, label):
    """The rows that prove a step clear bound the second derivative (and the slope's) of every monitor, gap and
    storey row, and of each storey's drift velocity, over the step, sampled densely from random states, ramps and
    plastic offsets, the particular motion taken out as the kernel takes it; and the flow is the exponential of the
    generator built here: for every pattern of yielding storeys the tables are made for."""
    scenes = {**_damped_scenes(three_storey, el_centro), **_yielding_scenes(three_storey, el_centro)}
    arrays = _scene_arrays(scenes[label])
    n = len(arrays["model"].load_vec)
    nf = len(arrays["model"].building.mass)
    assert len(arrays["clear"].masks) == (1 if arrays["yld"] is None else 1 + nf + nf * (nf - 1) // 2)
    for index, mask in enumerate(arrays["clear"].masks):
        clear = pattern(arrays["clear"], index)
        gen, _ = _true_generator(arrays, [i for i in range(nf) if mask >> i & 1])
        _bounds_hold(clear, gen, n, el_centro.dt)


def _bounds_hold(clear, gen, n, dt):
    """Both of each row's bounds (over |y|, and over the moduli of y's modal amplitudes read by clear.inv) hold,
    and the second is the tighter (at most the first, since |V^-1 y| <= |V^-1| |y|)."""
    times = np.linspace(0.0, dt, 201)
    props = [expm(gen * t) for t in times]
    rng = np.random.default_rng(7)
    exact = props[-1][: 2 * n]
    assert np.max(np.abs(clear.flow - exact)) <= 1e-13 * np.max(np.abs(exact))
    nmon = (len(clear.ends) - len(clear.half) - 2 * (gen.shape[0] - 2 * n - 2)) // 2
    slopes = np.zeros(len(clear.ends), dtype=bool)  # the rows of a slope: bounds per unit |f'|, not max |f|
    slopes[nmon : 2 * nmon] = True
    slopes[len(clear.ends) - (gen.shape[0] - 2 * n - 2) :] = True
    tighter = 0
    for _ in range(40):
        u0 = np.concatenate([rng.normal(0, 0.05, n), rng.normal(0, 0.5, n), rng.normal(0, 3.0, 1),
                             rng.normal(0, 300.0, 1), rng.normal(0, 0.01, gen.shape[0] - 2 * n - 2)])
        path = np.array([p @ u0 for p in props])
        f = path[:, 2 * n]
        y = u0[: 2 * n] - clear.part @ u0[2 * n :]
        scale = np.where(slopes, abs(u0[2 * n + 1]), np.max(np.abs(f)))
        second = path @ (clear.ends @ gen @ gen).T  # each row's h'' along the step
        loose = clear.bound[:, : 2 * n] @ np.abs(y) + clear.load * scale
        tight = clear.bound[:, 2 * n :] @ np.abs(clear.inv @ y) + clear.load * scale
        assert np.all(tight <= loose * (1 + 1e-12))
        for limit in (loose, tight):
            assert np.all(np.abs(second) <= limit * (1 + 1e-9) + 1e-12 * np.abs(second).max(axis=0))
        tighter += np.count_nonzero(tight < 0.5 * loose)
    assert tighter > 0  # the amplitudes' bound is worth its reading


def test_unstable_yielding_patterns_are_left_out(three_storey, el_centro):
    """A pattern of yielding storeys gets tables only where its stiffness (b k less P-delta's P / h on the storeys
    that yield) is positive definite: with 2 % hardening and heavy P-delta the bottom storey yielding is not; and
    none where a yielding storey has no stiffness left."""
    heavy = three_storey.yielding(0.01, 0.02, storey_height=np.full(3, 3.5), p_delta=True)
    arrays = _scene_arrays(Scene(heavy, (), el_centro, collapse_drift_ratio=0.1))
    nf = heavy.storeys
    stable = []
    for count in range(MOST_YIELDING + 1):
        for yielding in combinations(range(nf), count):
            gen, _ = _true_generator(arrays, yielding)
            stiffness = -gen[nf : 2 * nf, :nf] * arrays["model"].building.mass[:, None]
            if np.all(np.linalg.eigvalsh(0.5 * (stiffness + stiffness.T)) > 0.0):
                stable.append(sum(1 << i for i in yielding))
    assert 0 < len(stable) < 1 + nf + nf * (nf - 1) // 2  # some left out, the elastic one kept
    assert sorted(arrays["clear"].masks) == sorted(stable)
    # perfectly plastic storeys without P-delta: one yielding is a zero mode, whose particular motion is quadratic
    plastic = _scene_arrays(Scene(three_storey.yielding(0.01, 0.0), (), el_centro))
    assert list(plastic["clear"].masks) == [0]


@pytest.mark.parametrize("storeys, made", [(5, 1 + 5 + 10), (10, 1 + 10), (16, 1)])
def test_patterns_are_made_within_their_count(storeys, made, el_centro):
    """Every pattern of up to MOST_YIELDING storeys on five storeys (16 of them), each storey alone on ten (all
    pairs would be 56), none but the elastic one on sixteen: whole counts, within MOST_PATTERNS."""
    building = Building.uniform(storeys, 1.0, 0.02).yielding(0.01, 0.05)
    masks = _scene_arrays(Scene(building, (), el_centro))["clear"].masks
    assert len(masks) == made <= MOST_PATTERNS
    assert len(set(masks)) == made and masks[0] == 0
    assert max(bin(int(m)).count("1") for m in masks) == {5: 2, 10: 1, 16: 0}[storeys]


#: scale factors a few units of round-off from 1: the ensemble a run's own rounding could have produced
ROUND_OFF = tuple(1.0 + sign * k * 1e-15 for k in (1, 2, 3) for sign in (1, -1))


def _outcome(out) -> np.ndarray:
    """What a run ends with: its certified peaks, the end state, the energy terms, the largest energy (and a
    yielding building's plastic offsets and work)."""
    d = out["diag"]
    yld = out["yld"]
    storeys = [] if yld is None else [*yld.offset, d[L.D_PLASTIC]]
    energies = [d[L.D_WORK], d[L.D_VISC], d[L.D_IMPLOSS], d[L.D_EMAX]]
    return np.concatenate([out["peak"], out["q"], out["v"], energies, storeys])


@pytest.mark.parametrize("label", ["cid in 4 units and a tmd", "pid", "yielding, bare", "yielding, p-delta and a cid"])
def test_clear_steps_give_the_segments_motion(three_storey, el_centro, label):
    """The same run with and without the tables: the same impacts, yield events and segments, the peaks' times, and
    the certified peaks, the end state and the energy terms as close as the run's own round-off sensitivity allows;
    most steps taken clear.

    The sensitivity is the spread that a change of the record's scale by a few 1e-15 gives the run without the
    tables: after its impacts a unit's end position is known to 5e-5 m (the CID) and the PID run's end state to
    1.6e-6 of itself; with P-delta a storey's peak drift to 1.2e-9 of itself.  The tables are one more change of
    round-off's size, amplified as much: over 21 such scales each (measured 2026-11-30), the end states with and
    without them differed in mean by 1.4 (PID) and 0.5 (CID) of their standard deviations.  So each entry is held
    within three spreads of the run without them, or 1e-12 of itself where the spread is narrower."""
    scene = {**_damped_scenes(three_storey, el_centro), **_yielding_scenes(three_storey, el_centro)}[label]
    arrays = _scene_arrays(scene)
    fast, slow = run_arrays(arrays), run_arrays(dict(arrays, clear=None))
    d_fast, d_slow = fast["diag"], slow["diag"]
    assert d_fast[L.D_IMPACTS] == d_slow[L.D_IMPACTS]
    assert d_fast[L.D_YIELDS] == d_slow[L.D_YIELDS]
    assert d_fast[L.D_IMPACTS] + d_fast[L.D_YIELDS] > 0
    assert d_fast[L.D_SEGMENTS] == d_slow[L.D_SEGMENTS]
    # most steps, on yielding branches too (the bare yielding run: 93 % clear, measured 2026-12-01)
    assert d_slow[L.D_CLEAR] == 0 and d_fast[L.D_CLEAR] >= 0.85 * d_fast[L.D_SEGMENTS]
    # a stroke at its wall reads its cap at every impact, to round-off: which impact's reading is the largest is
    # round-off's choice, so the time of a peak at its cap is not compared (the peak is, below)
    capped = np.isclose(slow["peak"], arrays["model"].monitors.cap, rtol=1e-12, atol=0)
    assert np.allclose(fast["peak_t"][~capped], slow["peak_t"][~capped], rtol=0, atol=1e-9)
    ensemble = np.array([_outcome(slow)] + [
        _outcome(run_arrays(dict(_scene_arrays(replace(scene, load=GroundMotion(el_centro.accel * f, el_centro.dt))),
                                 clear=None))) for f in ROUND_OFF])
    width = ensemble.max(axis=0) - ensemble.min(axis=0)
    assert np.any(width > 0.0)  # the scales reach the run
    assert np.all(np.abs(_outcome(fast) - ensemble[0]) <= 3.0 * width + 1e-12 * np.abs(ensemble[0]))
    assert abs(simulate_scene(scene).diagnostics["energy_residual"]) <= 1e-12


def test_yielding_branches_are_taken_clear(three_storey, el_centro):
    """A storey on its yielding branch no longer sends a step to the segments: with the yielding patterns' tables
    the bare yielding run takes more steps clear than with the elastic pattern's alone (most of those it left),
    with the same yield events, and its plastic work the same to round-off (the comparison with no tables at all,
    within the run's own sensitivity, is test_clear_steps_give_the_segments_motion's)."""
    scene = _yielding_scenes(three_storey, el_centro)["yielding, bare"]
    arrays = _scene_arrays(scene)
    model = arrays["model"]
    elastic = clear_step_tables(model.building, model.units, arrays["springs"], arrays["yld"], model.load_vec,
                                el_centro.dt, model.monitors, most_yielding=0)
    assert list(elastic.masks) == [0] and len(arrays["clear"].masks) == 7
    full = run_arrays(arrays)
    alone = run_arrays(dict(_scene_arrays(scene), clear=elastic))
    assert full["diag"][L.D_YIELDS] == alone["diag"][L.D_YIELDS] > 0
    left = alone["diag"][L.D_SEGMENTS] - alone["diag"][L.D_CLEAR]
    gained = full["diag"][L.D_CLEAR] - alone["diag"][L.D_CLEAR]
    assert gained > 0.5 * left
    assert full["diag"][L.D_PLASTIC] == pytest.approx(alone["diag"][L.D_PLASTIC], rel=1e-9)


def test_samples_and_the_window_start_are_left_to_the_segments(three_storey, el_centro):
    """A step holding a sample, or cut by the window's start, is not taken clear: the samples come from the
    segment's rows, and a run sampled at every record step takes no clear step at all."""
    scene = Scene(three_storey, (), el_centro)
    every = np.arange(0.0, scene.t_end, el_centro.dt)
    sampled = simulate_scene(scene, times=every)
    assert sampled.diagnostics["clear_steps"] == 0
    plain = simulate_scene(scene)
    assert plain.diagnostics["clear_steps"] > 0.9 * plain.diagnostics["segments"]
    assert sampled.peak_roof_displacement == pytest.approx(plain.peak_roof_displacement, rel=1e-12)
    assert sampled.rms_roof_displacement == pytest.approx(plain.rms_roof_displacement, rel=1e-12)


def test_monitors_rows_are_the_scene_monitors(three_storey, el_centro):
    """Each monitor's row over the state reads what the run reports: the roof's displacement and absolute
    acceleration and each drift, at the state the run ends in."""
    scene = Scene(three_storey, (), el_centro, duration=7.0)
    arrays = _scene_arrays(scene)
    out = run_arrays(arrays)
    clear = pattern(arrays["clear"], 0)
    u = np.concatenate([out["q"], out["v"], [0.0, 0.0]])
    values = clear.ends @ u
    assert values[0] == out["q"][2]
    assert np.allclose(values[2:5], np.diff(np.concatenate([[0.0], out["q"]])), rtol=0, atol=1e-15)
    model = arrays["model"]
    accel = -np.linalg.solve(np.diag(model.building.mass), model.building.stiffness @ out["q"]
                             + model.building.damping @ out["v"])
    assert values[1] == pytest.approx(accel[2], rel=1e-12)


def test_a_row_is_read_with_the_loads_slope_and_the_plastic_offsets(three_storey, el_centro):
    """The kernel's reading of a row at a step's ends (clear_step._row_ends) is the row times the state: the roof's
    acceleration's slope, which the record's slope enters, and a yielding building's rows, which its plastic offsets
    enter."""
    scene = _yielding_scenes(three_storey, el_centro)["yielding, p-delta and a cid"]
    # a force on the floors, whose absolute acceleration (unlike a ground motion's) the record's slope enters
    scene = replace(scene, load=ForceRecord(el_centro.accel * 1e5, el_centro.dt, [1.0, 1.0, 1.0]))
    clear = pattern(_scene_arrays(scene)["clear"], 0)
    n2 = clear.flow.shape[0]
    rng = np.random.default_rng(3)
    u = rng.normal(0.0, 1.0, clear.flow.shape[1])
    nxt = clear.flow @ u
    r_end = u[n2] + u[n2 + 1] * el_centro.dt
    after = np.concatenate([nxt, [r_end], u[n2 + 1 :]])
    absy = np.abs(rng.normal(0.0, 1.0, clear.bound.shape[1]))
    rows = clear.ends
    for tight in (False, True):
        for m in range(len(rows)):
            h0, h1, reach = _row_ends(rows, clear.bound, m, u, nxt, absy, u[n2], r_end, tight)
            assert h0 == pytest.approx(rows[m] @ u, rel=1e-12, abs=1e-12 * np.abs(rows[m]) @ np.abs(u))
            assert h1 == pytest.approx(rows[m] @ after, rel=1e-12, abs=1e-12 * np.abs(rows[m]) @ np.abs(after))
            columns = slice(n2, None) if tight else slice(0, n2)
            assert reach == pytest.approx(clear.bound[m, columns] @ absy[columns], rel=1e-12)
    assert np.any(rows[:, n2 + 1] != 0.0)  # the acceleration's slope reads the load's
    assert np.any(rows[:, n2 + 2 :] != 0.0)  # the acceleration reads the plastic offsets
