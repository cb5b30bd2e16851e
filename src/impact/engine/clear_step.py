"""Whole record steps that provably hold no event and raise no peak, taken by matrices.

Between two samples a record is a ramp, so over a whole step of a linear scene the state moves by a fixed
matrix of the state and the ramp's two values, the matrix exponential of the scene's first-order system
augmented by the load and its slope (Van Loan's first-order hold), and the load's work, the viscous dissipation
and the roof's square over the step are fixed quadratic forms of the same vector (Van Loan's integrals of a
quadratic form).  Made once per scene for its configuration with every unit free, they take a step in a few
hundred operations instead of the segment's modal rows, tables, searches and integrals.

A step may be taken so only when nothing the segment machinery certifies can happen in it: no unit reaching a
wall and no monitor passing its running peak.  Both are proved by the test the segment's own searches open
with (scene_loop._clear_of_walls, monitor_modal): a row h with |h''| <= M over the step stays within
max(h(0), h(tau)) + M tau^2 / 8 and min(h(0), h(tau)) - M tau^2 / 8.  M bounds the modes of the homogeneous
motion, |h''| <= sum_k |c V_k| |kappa_k|^2 |w_k| with w the modal amplitudes and |w| <= |V^-1| |y|, y the state
less the ramp's particular motion (linear in time, so adding nothing to h''): one nonnegative row per row of
the scene.  A unit without a spring has no mode: its flight is the load's, q'' = (l / m) f, bounded by max |f|.
A step that fails the test is the segment machinery's as before (scene_loop.run_scene), from the same state.

The state, the work and the dissipation so taken differ from the modal rows' by round-off only; the tests hold
the two to each other, to an independent solution and to the energy balance.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.linalg import expm

from impact.engine.bundles import ClearStep
from impact.engine.events import PEAK_RTOL
from impact.engine.layout import D_CLEAR, D_EMAX, D_SEGMENTS, D_VISC, D_WORK, MON_DISP, P_REC_DT, UNIT_WALLS
from impact.engine.segment import energy, record_value, storey_gravity, whole_step

#: how far inside its walls a unit's gap row must stay over a clear step, relative to the gap and the positions
#: it is the difference of: a thousand times the contact tolerance the wall search resolves to (contact.CONTACT_TOL)
WALL_MARGIN = 1e-9


#: the most a mode may decay over a step, |Re kappa| dt, for the step's integrals to keep their digits: Van Loan's
#: grow the mode's exponential to exp(|Re kappa| dt) and cancel it back, so their round-off grows by up to that
#: (55 at 4); a scene with a faster-decaying mode (a stiff, heavily damped storey) takes every step by the segments
MAX_DECAY = 4.0
MAX_DECAY = 4.0

#: tables made, by what they were made from: a study runs one building and damper under many records and levels
_MADE: dict = {}
_MADE_MAX = 64


def clear_step_tables(building, units, springs, yld, load_vec: np.ndarray, dt: float, monitors) -> ClearStep | None:
    """The tables of a whole record step of the scene with every unit free and every storey elastic,
    M q'' + C q' + K q = load_vec f(t) + G p with f a ramp over [0, dt] and p the storeys' plastic offsets, for the
    state u = (q, q', f(0), f', p); building, units, springs, yld, monitors: the scene's bundles
    (bundles.BuildingArrays, UnitArrays, SpringArrays or None, YieldArrays or None, MonitorArrays, whose first row
    is the roof's displacement, the one the window squares).  None where no step can be taken so: a unit with a
    dashpot and no spring (its flight is not the load's alone) or storeys whose elastic branches, with P-delta,
    are not stable.  Made once per set of inputs (a run only reads them)."""
    law = () if yld is None else (yld.stiffness, yld.hardening, yld.yield_drift, yld.geometric, yld.limit)
    inputs = (*building, *units, *(springs or ()), *law, load_vec, monitors.rows, monitors.kind, monitors.record_coef)
    key = (dt, springs is None, yld is None, *(a.tobytes() for a in inputs))
    if key not in _MADE:
        if len(_MADE) >= _MADE_MAX:
            del _MADE[next(iter(_MADE))]
        _MADE[key] = _make_tables(building, units, springs, yld, load_vec, dt, monitors)
    return _MADE[key]


def _make_tables(building, units, springs, yld, load_vec, dt, monitors) -> ClearStep | None:
    mass, stiffness, damping = _free_configuration(building, units, springs, yld)
    flying = np.diag(stiffness) == 0.0  # a unit without a spring: no mode, its flight a polynomial
    if np.any(flying & (np.diag(damping) != 0.0)):
        return None
    if np.any(np.linalg.eigvalsh(stiffness[np.ix_(~flying, ~flying)]) <= 0.0):
        return None
    n = len(mass)
    nf = len(building.mass)
    offsets = _offset_forces(n, yld)
    generator = _generator(mass, stiffness, damping, load_vec, offsets)
    if np.max(np.abs(np.linalg.eigvals(generator[: 2 * n, : 2 * n]).real)) * dt > MAX_DECAY:
        return None
    size = generator.shape[0]
    flow = expm(generator * dt)[: 2 * n, :].copy()
    roof = np.zeros(size)
    roof[:n] = monitors.rows[0]
    work = np.zeros((size, size))
    work[2 * n, n : 2 * n] = work[n : 2 * n, 2 * n] = 0.5 * load_vec
    visc = np.zeros_like(work)
    visc[n : 2 * n, n : 2 * n] = damping
    forms = [_integral_of_form(generator, s, dt) for s in (work, visc, np.outer(roof, roof))]
    part, modes = _reach(mass, stiffness, damping, load_vec, offsets, flying, dt)
    walled = np.flatnonzero(units.kind & UNIT_WALLS)
    bands = np.zeros((len(walled) + offsets.shape[1], n))  # each walled unit's gap, then each storey's drift
    bands[np.arange(len(walled)), nf + walled] = 1.0
    bands[np.arange(len(walled)), units.floor[walled]] = -1.0
    for i in range(offsets.shape[1]):
        bands[len(walled) + i, i] = 1.0
        if i > 0:
            bands[len(walled) + i, i - 1] = -1.0
    peaks = _rows(generator, monitors.rows, monitors.kind, monitors.record_coef, modes)
    slopes = _rows(generator, monitors.rows, monitors.kind, monitors.record_coef, modes, slope=True)
    band_rows = _rows(generator, bands, np.full(len(bands), MON_DISP), np.zeros(len(bands)), modes)
    return ClearStep(flow, *forms, part, *peaks, *slopes, *band_rows, 0.5 * units.gap[walled],
                     _twins(units, springs, nf))


def _offset_forces(n: int, yld) -> np.ndarray:
    """(n, storeys): the force on each degree of freedom per unit of each storey's plastic offset p on its elastic
    branch, whose restoring force is k u - (1 - b) k p (none for an elastic building)."""
    storeys = 0 if yld is None else len(yld.stiffness)
    g = np.zeros((n, storeys))
    for i in range(storeys):
        pull = (1.0 - yld.hardening[i]) * yld.stiffness[i]
        g[i, i] = pull
        if i > 0:
            g[i - 1, i] = -pull
    return g


def _free_configuration(building, units, springs, yld):
    """M, K and C over the floors and the units, every unit free (a unit's spring and dashpot join it to its
    floor) and every storey elastic (its stiffness k less P-delta's P / h)."""
    nf = len(building.mass)
    n = nf + len(units.mass)
    stiffness = np.zeros((n, n))
    damping = np.zeros((n, n))
    stiffness[:nf, :nf] = building.stiffness
    damping[:nf, :nf] = building.damping
    if yld is not None:
        for i, g in enumerate(yld.geometric):
            floors = [i - 1, i] if i > 0 else [i]
            stiffness[np.ix_(floors, floors)] -= g * (np.array([[1.0, -1.0], [-1.0, 1.0]]) if i > 0 else 1.0)
    if springs is not None:
        for j, f in enumerate(units.floor):
            u = nf + j
            for matrix, value in ((stiffness, springs.stiffness[j]), (damping, springs.damping[j])):
                matrix[u, u] += value
                matrix[f, f] += value
                matrix[u, f] -= value
                matrix[f, u] -= value
    return np.concatenate([building.mass, units.mass]), stiffness, damping


def _twins(units, springs, nf: int) -> np.ndarray:
    """Per degree of freedom, the unit before it if it is the same unit (its twin, whose motion it copies to the
    bit while the two are in the same state, as the segment's rows do), else -1: a damper of several units moves
    as one."""
    twin = np.full(nf + len(units.mass), -1, dtype=np.int64)
    fields = list(units) + (list(springs) if springs is not None else [])
    for j in range(1, len(units.mass)):
        if all(a[j] == a[j - 1] for a in fields):
            twin[nf + j] = nf + j - 1
    return twin


def _generator(mass, stiffness, damping, load_vec, offsets=None) -> np.ndarray:
    """d/dt of u = (q, q', f, f', p): the scene's first-order system, driven by f, whose slope is constant, and by
    the storeys' plastic offsets p (constant on elastic branches; offsets: their forces, _offset_forces)."""
    n = len(mass)
    held = 0 if offsets is None else offsets.shape[1]
    m_inv = 1.0 / mass[:, None]
    gen = np.zeros((2 * n + 2 + held, 2 * n + 2 + held))
    gen[:n, n : 2 * n] = np.eye(n)
    gen[n : 2 * n, :n] = -m_inv * stiffness
    gen[n : 2 * n, n : 2 * n] = -m_inv * damping
    gen[n : 2 * n, 2 * n] = load_vec / mass
    gen[2 * n, 2 * n + 1] = 1.0
    if held:
        gen[n : 2 * n, 2 * n + 2 :] = m_inv * offsets
    return gen


def _integral_of_form(generator: np.ndarray, form: np.ndarray, dt: float) -> np.ndarray:
    """Q with u(0)^T Q u(0) = integral over [0, dt] of u(t)^T S u(t) dt (Van Loan, 1978), symmetrised."""
    size = generator.shape[0]
    block = np.zeros((2 * size, 2 * size))
    block[:size, :size] = -generator.T
    block[:size, size:] = form
    block[size:, size:] = generator
    e = expm(block * dt)
    q = e[size:, size:].T @ e[:size, size:]
    return 0.5 * (q + q.T)


def _reach(mass, stiffness, damping, load_vec, offsets, flying, dt):
    """The particular motion at the step's start per unit f(0), per unit slope f' and per unit of each storey's
    offset ((2n, 2 + storeys), zero for the units without a spring), and the modes of every other degree of freedom
    as _rows reads them.  The particular motion is q_p = a0 + a1 t with K a1 = l f' and K a0 + C a1 = l f(0) + G p."""
    n = len(mass)
    modal = np.flatnonzero(~flying)
    k, c, l = stiffness[np.ix_(modal, modal)], damping[np.ix_(modal, modal)], load_vec[modal]
    per_slope = np.linalg.solve(k, l)
    part = np.zeros((2 * n, 2 + offsets.shape[1]))
    part[modal, 0] = per_slope
    part[modal, 1] = -np.linalg.solve(k, c @ per_slope)
    part[n + modal, 1] = per_slope
    if offsets.shape[1]:
        part[modal, 2:] = np.linalg.solve(k, offsets[modal])
    kap, vec = np.linalg.eig(_generator(mass[modal], k, c, l)[: 2 * len(modal), : 2 * len(modal)])
    growth = np.maximum(1.0, np.exp(kap.real * dt))
    return part, (modal, kap, vec, np.abs(np.linalg.inv(vec)), growth, np.where(flying, load_vec / mass, 0.0))


def _rows(generator, rows, kinds, record_coef, modes, slope=False):
    """Per row over q (a monitor of layout.MON_* kind, or a unit's gap): its value as a row over u (ends), the
    nonnegative row over |u - particular| bounding its second derivative over the step (bound), and what the units
    without a spring add to that bound per unit of max |f| over the step (load_bound).  slope: the same for the
    row's first derivative (its bound's load part per unit of |f'|)."""
    modal, kap, vec, vinv_abs, growth, flight = modes
    size = generator.shape[0]
    n = rows.shape[1]
    states = np.concatenate([modal, n + modal])
    ends = np.zeros((len(kinds), size))
    bound = np.zeros((len(kinds), 2 * n))
    load_bound = np.zeros(len(kinds))
    for m, (row, kind) in enumerate(zip(rows, kinds)):
        if kind == MON_DISP:
            ends[m, :n] = row
            power = 2
            load_bound[m] = abs(row @ flight)
        else:  # an absolute acceleration: the row of q'' and the record's own term; a flight's fourth derivative is 0
            ends[m] = row @ generator[n : 2 * n]
            ends[m, 2 * n] += record_coef[m]
            power = 4
        if slope:
            ends[m] = ends[m] @ generator
            power += 1
        weights = np.abs(row[modal] @ vec[: len(modal)]) * np.abs(kap) ** power * growth
        bound[m, states] = weights @ vinv_abs
    return ends, bound, load_bound


@njit(cache=True, inline="always")
def _form(q, u):
    """u^T Q u of a symmetric Q."""
    acc = 0.0
    for i in range(u.shape[0]):
        ui = u[i]
        if ui != 0.0:
            row = 0.5 * q[i, i] * ui
            for j in range(i + 1, u.shape[0]):
                row += q[i, j] * u[j]
            acc += ui * row
    return 2.0 * acc


@njit(cache=True, inline="always")
def _row_ends(ends, bound, m, u, nxt, absy, r0, r_end):
    """Row m at the step's start and end, and its modes' bound on |h''| over the step; u: the step's start
    (q, q', f(0), f', p), nxt: its end's (q, q'), r_end: f at its end."""
    n2 = absy.shape[0]
    h0 = ends[m, n2] * r0
    h1 = ends[m, n2] * r_end
    for j in range(n2 + 1, u.shape[0]):  # the load's slope and the plastic offsets, constant over the step
        h0 += ends[m, j] * u[j]
        h1 += ends[m, j] * u[j]
    reach = 0.0
    for j in range(n2):
        h0 += ends[m, j] * u[j]
        h1 += ends[m, j] * nxt[j]
        reach += bound[m, j] * absy[j]
    return h0, h1, reach


@njit(cache=True, inline="always")
def _advance(flow, part, twin, u, nxt, absy):
    """The state at the step's end into nxt (a unit in its twin's state gets its twin's, to the bit), and
    |u - particular| into absy."""
    n2 = nxt.shape[0]
    n = n2 // 2
    for i in range(n2):
        acc = 0.0
        for j in range(u.shape[0]):
            acc += flow[i, j] * u[j]
        nxt[i] = acc
        y = u[i]
        for c in range(part.shape[1]):
            y -= part[i, c] * u[n2 + c]
        absy[i] = abs(y)
    for i in range(n):
        k = twin[i]
        if k >= 0 and u[i] == u[k] and u[n + i] == u[n + k]:
            nxt[i] = nxt[k]
            nxt[n + i] = nxt[n + k]


@njit(cache=True, inline="always")
def _bands(half, yld, lo, hi):
    """Each band row's ends: a walled unit's walls, then each storey's elastic band, d_y about its plastic offset
    and within its collapse limit."""
    walls = half.shape[0]
    for r in range(walls):
        lo[r] = -half[r]
        hi[r] = half[r]
    if yld is not None:
        for i in range(yld.offset.shape[0]):
            lo[walls + i] = max(yld.offset[i] - yld.yield_drift[i], -yld.limit[i])
            hi[walls + i] = min(yld.offset[i] + yld.yield_drift[i], yld.limit[i])


@njit(cache=True)
def clear_steps(clear, scratch, state, peaks, load, times, building, units, springs, yld):
    """Whole record steps by the tables from t for as long as each is clear: whole, not cut by the window's start
    nor holding a sample, no unit reaching a wall and no storey the end of its elastic band, and every monitor
    either within its running peak or monotone over the step (its new peak then at an end); returns the time they
    reached, the state moved, the work and the dissipation booked in diag, the roof's square in x2 where a step
    is in the window.  load: (the run's parameters, the record); times: (t, the run's end, the window's start, the
    next sample's time); state: (q, v, diag);
    peaks: (each monitor's running peak, its time, its cap, its window square); scratch: (u, the next state,
    |y|, a monitor's value at an end that raises its peak and the time from the step's start, -1 where none, each
    band's lower and upper end); building, units, springs (None without), yld (None: elastic): the scene's, whose
    energy the largest-energy diagnostic reads.  The bundles are unpacked once: unpacked on every step, each of
    their arrays cost a reference count there."""
    flow, work, visc, square, part, ends, bound, load_bound, slope_ends, slope_bound, slope_load, band_ends, \
        band_bound, band_load, half, twin = clear
    u, nxt, absy, top, at, lo, hi = scratch
    q, v, diag = state
    peak, peak_t, cap, x2 = peaks
    t, t_end, t_square, t_sample = times
    p, record = load
    nf = building.mass.shape[0]
    n = q.shape[0]
    _bands(half, yld, lo, hi)
    if yld is not None:
        for i in range(yld.offset.shape[0]):
            u[2 * n + 2 + i] = yld.offset[i]
    while True:
        r0, r1, t_next = record_value(record, p, t)
        tau = whole_step(p, t, t_next, t_end)
        if tau != p[P_REC_DT] or t < t_square < t_next or t_sample <= t_next:
            return t
        for i in range(n):
            u[i] = q[i]
            u[n + i] = v[i]
        u[2 * n] = r0
        u[2 * n + 1] = r1
        _advance(flow, part, twin, u, nxt, absy)
        r_end = r0 + r1 * tau
        spread = tau * tau / 8.0
        f_max = max(abs(r0), abs(r_end))
        for r in range(lo.shape[0]):
            if hi[r] - lo[r] == np.inf:
                continue  # a storey that neither yields nor collapses
            h0, h1, reach = _row_ends(band_ends, band_bound, r, u, nxt, absy, r0, r_end)
            size = 0.0
            for j in range(n):
                size += abs(band_ends[r, j] * u[j])
            # inside by the margin of the band and of the positions the row is the difference of
            margin = WALL_MARGIN * (min(hi[r] - lo[r], 2.0 * (abs(h0) + abs(h1))) + size + abs(h1 - h0))
            bulge = (reach + band_load[r] * f_max) * spread + margin
            if max(h0, h1) + bulge >= hi[r] or min(h0, h1) - bulge <= lo[r]:
                return t
        for m in range(ends.shape[0]):
            at[m] = -1.0
            if not peak[m] < cap[m]:
                continue  # not searched: a stroke at its wall, or a run not asked for it
            h0, h1, reach = _row_ends(ends, bound, m, u, nxt, absy, r0, r_end)
            if max(abs(h0), abs(h1)) + (reach + load_bound[m] * f_max) * spread <= peak[m] * (1.0 + PEAK_RTOL):
                continue
            # it may pass its peak: where its slope keeps its sign, its extremes are at the ends
            d0, d1, reach = _row_ends(slope_ends, slope_bound, m, u, nxt, absy, r0, r_end)
            if d0 * d1 <= 0.0 or min(abs(d0), abs(d1)) <= (reach + slope_load[m] * abs(r1)) * spread:
                return t
            if max(abs(h0), abs(h1)) > peak[m]:
                top[m] = max(abs(h0), abs(h1))
                at[m] = tau if abs(h1) >= abs(h0) else 0.0
        for m in range(ends.shape[0]):
            if at[m] >= 0.0:
                peak[m] = top[m]
                peak_t[m] = t + at[m]
        diag[D_WORK] += _form(work, u)
        diag[D_VISC] += _form(visc, u)
        if t_next > t_square:
            x2[0] += _form(square, u)
        for i in range(n):
            q[i] = nxt[i]
            v[i] = nxt[n + i]
        diag[D_SEGMENTS] += 1.0
        diag[D_CLEAR] += 1.0
        e_now = energy(building, units, springs, yld, nf, q, v)
        if yld is not None:
            e_now += storey_gravity(yld, q)  # as scene_loop.move_to_end counts the balance's scale
        diag[D_EMAX] = max(diag[D_EMAX], e_now)
        t = t_next
