"""Whole record steps by matrices (impact.engine.clear_step): the same motion, energy and certified peaks as the
segment's modal rows, to round-off, with every step they take proved clear of walls and of the peaks."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.linalg import expm

from impact.closed_form.propagator import first_order_hold
from impact.engine import layout as L
from impact.engine.clear_step import _generator
from impact.engine.scenes import _scene_arrays, run_arrays, simulate_scene
from impact.model.building import Building
from impact.model.records import load_record
from impact.model.scene import Damper, GroundMotion, Scene


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


def test_the_flow_is_the_first_order_hold(three_storey, el_centro):
    """The tables' flow over (q, q', f(0), f') is the propagator's x_{k+1} = A x_k + B0 a_k + B1 a_{k+1}: with
    f' = (a_{k+1} - a_k) / dt, its f(0) column is B0 + B1 and its f' column B1 dt."""
    clear = _scene_arrays(Scene(three_storey, (), el_centro))["clear"]
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
    clear, load_vec = arrays["clear"], arrays["model"].load_vec
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


def _true_generator(arrays):
    """The scene's generator over (q, q', f, f') with every unit free, and its damping matrix, built here from the
    scene's own arrays."""
    model, springs = arrays["model"], arrays["springs"]
    nf = len(model.building.mass)
    n = len(model.load_vec)
    mass = np.concatenate([model.building.mass, model.units.mass])
    k = np.zeros((n, n))
    c = np.zeros((n, n))
    k[:nf, :nf] = model.building.stiffness
    c[:nf, :nf] = model.building.damping
    for j, f in enumerate(model.units.floor):
        for matrix, value in ((k, springs.stiffness[j]), (c, springs.damping[j])):
            matrix[np.ix_([f, nf + j], [f, nf + j])] += value * np.array([[1.0, -1.0], [-1.0, 1.0]])
    return _generator(mass, k, c, model.load_vec), c


@pytest.mark.parametrize("label", ["cid in 4 units and a tmd", "pid"])
def test_the_bounds_hold_over_a_step(three_storey, el_centro, label):
    """The rows that prove a step clear bound the second derivative (and the slope's) of every monitor and gap
    row over the step, sampled densely from random states and ramps, the particular motion taken out as the
    kernel takes it."""
    arrays = _scene_arrays(_damped_scenes(three_storey, el_centro)[label])
    clear, model = arrays["clear"], arrays["model"]
    gen, _ = _true_generator(arrays)
    n = len(model.load_vec)
    dt = el_centro.dt
    times = np.linspace(0.0, dt, 201)
    props = [expm(gen * t) for t in times]
    rng = np.random.default_rng(7)
    for _ in range(40):
        u0 = np.concatenate([rng.normal(0, 0.05, n), rng.normal(0, 0.5, n), rng.normal(0, 3.0, 1),
                             rng.normal(0, 300.0, 1)])
        path = np.array([p @ u0 for p in props])
        f = path[:, 2 * n]
        absy = np.abs(u0[: 2 * n] - clear.part @ u0[2 * n:])
        for ends, bound, load, scale in ((clear.ends, clear.bound, clear.load_bound, np.max(np.abs(f))),
                                         (clear.slope_ends, clear.slope_bound, clear.slope_load, abs(u0[-1])),
                                         (clear.wall_ends, clear.wall_bound, clear.wall_load, np.max(np.abs(f)))):
            second = path @ (ends @ gen @ gen).T  # each row's h'' along the step
            limit = bound @ absy + load * scale
            assert np.all(np.abs(second) <= limit * (1 + 1e-9) + 1e-12 * np.abs(second).max())


#: scale factors a few units of round-off from 1: the ensemble a run's own rounding could have produced
ROUND_OFF = tuple(1.0 + sign * k * 1e-15 for k in (1, 2, 3) for sign in (1, -1))


def _outcome(out) -> np.ndarray:
    """What a run ends with: the end state, the energy terms, the largest energy."""
    d = out["diag"]
    return np.concatenate([out["q"], out["v"], [d[L.D_WORK], d[L.D_VISC], d[L.D_IMPLOSS], d[L.D_EMAX]]])


@pytest.mark.parametrize("label", ["cid in 4 units and a tmd", "pid"])
def test_clear_steps_give_the_segments_motion(three_storey, el_centro, label):
    """The same run with and without the tables: the same impacts and segments, the certified peaks and their
    times to round-off, and the end state and the energy terms as close as the run's own round-off sensitivity
    allows; most steps taken clear.

    The sensitivity is the spread that a change of the record's scale by a few 1e-15 gives the run without the
    tables: after its impacts a unit's end position is known to 5e-5 m (the CID) and the PID run's end state to
    1.6e-6 of itself.  The tables are one more change of round-off's size, amplified as much: over 21 such scales
    each (measured 2026-11-30), the end states with and without them differed in mean by 1.4 (PID) and 0.5 (CID)
    of their standard deviations.  So each entry is held within three spreads of the run without them."""
    scene = _damped_scenes(three_storey, el_centro)[label]
    arrays = _scene_arrays(scene)
    fast, slow = run_arrays(arrays), run_arrays(dict(arrays, clear=None))
    d_fast, d_slow = fast["diag"], slow["diag"]
    assert d_fast[L.D_IMPACTS] == d_slow[L.D_IMPACTS] > 0
    assert d_fast[L.D_SEGMENTS] == d_slow[L.D_SEGMENTS]
    assert d_slow[L.D_CLEAR] == 0 and d_fast[L.D_CLEAR] >= 0.8 * d_fast[L.D_SEGMENTS]
    assert np.allclose(fast["peak"], slow["peak"], rtol=1e-12, atol=0)
    assert np.allclose(fast["peak_t"], slow["peak_t"], rtol=0, atol=1e-9)
    ensemble = np.array([_outcome(slow)] + [
        _outcome(run_arrays(dict(_scene_arrays(replace(scene, load=GroundMotion(el_centro.accel * f, el_centro.dt))),
                                 clear=None))) for f in ROUND_OFF])
    width = ensemble.max(axis=0) - ensemble.min(axis=0)
    assert np.all(width > 0.0)  # the ensemble resolves every entry's sensitivity
    assert np.all(np.abs(_outcome(fast) - ensemble[0]) <= 3.0 * width)
    assert abs(simulate_scene(scene).diagnostics["energy_residual"]) <= 1e-12


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
    clear = arrays["clear"]
    u = np.concatenate([out["q"], out["v"], [0.0, 0.0]])
    values = clear.ends @ u
    assert values[0] == out["q"][2]
    assert np.allclose(values[2:5], np.diff(np.concatenate([[0.0], out["q"]])), rtol=0, atol=1e-15)
    model = arrays["model"]
    accel = -np.linalg.solve(np.diag(model.building.mass), model.building.stiffness @ out["q"]
                             + model.building.damping @ out["v"])
    assert values[1] == pytest.approx(accel[2], rel=1e-12)
