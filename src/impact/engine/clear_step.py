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
motion, |h''| <= sum_k |c V_k| |kappa_k|^2 |w_k| with w = V^-1 y the modal amplitudes of y, the state less the
ramp's particular motion (linear in time, so adding nothing to h''): two nonnegative rows per row of the scene,
one over |y| (|w| <= |V^-1| |y|, as cheap as the row) and one over |w| itself, read only where the first cannot
prove the step (beside a soft storey y lies almost all in the slow modes, which |V^-1| |y| spreads over the fast).
A unit without a spring has no mode: its flight is the load's, q'' = (l / m) f, bounded by max |f|.  A step that
fails the test is the segment machinery's as before (scene_loop.run_scene), from the same state.

A yielding building's storeys are each on a branch, elastic or yielding, and between events each branch is
linear: the tables are made for every pattern of yielding storeys up to MOST_YIELDING at once (within
MOST_PATTERNS), stacked (a yielding storey's stiffness taken down to b k, its perfectly plastic element's constant
force s (1 - b) k d_y entering as an offset of -s d_y).  On a yielding branch the step must also keep the storey's drift velocity's sign
(else it unloads within it), proved by the same test on the drift's slope; its offset then follows its drift and
its plastic work is exact (segment.plastic_flow), as on a segment.

The state, the work and the dissipation so taken differ from the modal rows' by round-off only; the tests hold
the two to each other, to an independent solution and to the energy balance.
"""

from __future__ import annotations

from itertools import combinations
from math import comb

import numpy as np
from numba import njit
from scipy.linalg import expm

from impact.engine.bundles import ClearStep
from impact.engine.events import PEAK_RTOL, raise_peak
from impact.engine.layout import (
    BRANCH_ELASTIC,
    D_CLEAR,
    D_EMAX,
    D_SEGMENTS,
    D_VISC,
    D_WORK,
    MON_DISP,
    P_REC_DT,
    UNIT_WALLS,
)
from impact.engine.segment import (
    energy,
    join,
    plastic_flow,
    record_value,
    same_unit,
    storey_gravity,
    storey_stiffness,
    whole_step,
)

#: how far inside its walls a unit's gap row must stay over a clear step, relative to the gap and the positions
#: it is the difference of: a thousand times the contact tolerance the wall search resolves to (contact.CONTACT_TOL)
WALL_MARGIN = 1e-9


#: the most a mode may decay over a step, |Re kappa| dt, for the step's integrals to keep their digits: Van Loan's
#: grow the mode's exponential to exp(|Re kappa| dt) and cancel it back, so their round-off grows by up to that
#: (55 at 4); a scene with a faster-decaying mode (a stiff, heavily damped storey) takes every step by the segments
MAX_DECAY = 4.0

#: the most storeys on a yielding branch at once that a scene's tables are made for: each pattern is a matrix
#: exponential and three of twice its size, made once per scene, and most yielding steps have one storey or two
MOST_YIELDING = 2

#: the most patterns a scene's tables are made for: they are taken by their count of yielding storeys, a whole
#: count at a time, while they number at most this (one to five storeys: every pattern of two or fewer, 16 on
#: five; six to fifteen: each storey alone).  Each costs four matrix exponentials of up to twice the state's size,
#: which for a large scene outgrows a short run (a probe's ten storeys with three dampers: 56 patterns, 2.1 s).
#: So a pattern's mask (a bit per yielding storey) never needs more than 15 bits.
MOST_PATTERNS = 16

#: |y| = |u - particular| is rounded to this much of the terms it is the difference of, which the bounds add back
#: (beside a soft yielding storey the particular motion is far larger than the motion)
_ROUNDING = 1e-14

#: tables made, by what they were made from: a study runs one building and damper under many records and levels
_MADE: dict = {}
_MADE_MAX = 64


def clear_step_tables(building, units, springs, yld, load_vec: np.ndarray, dt: float, monitors,
                      most_yielding: int = MOST_YIELDING) -> ClearStep | None:
    """The tables of a whole record step of the scene with every unit free, for each pattern of its storeys'
    branches it is made for (every storey elastic, and up to most_yielding storeys yielding at once, within
    MOST_PATTERNS), stacked:
    M q'' + C q' + K q = load_vec f(t) + G p with f a ramp over [0, dt] and p the storeys' plastic offsets (a
    yielding storey's -s d_y), for the state u = (q, q', f(0), f', p); building, units, springs, yld, monitors:
    the scene's bundles (bundles.BuildingArrays, UnitArrays, SpringArrays or None, YieldArrays or None,
    MonitorArrays, whose first row is the roof's displacement, the one the window squares).  None where no step
    can be taken so: a unit with a dashpot and no spring (its flight is not the load's alone) or storeys whose
    elastic branches, with P-delta, are not stable; a yielding pattern that is not stable is left out.  Made once
    per set of inputs (a run only reads them)."""
    law = () if yld is None else (yld.stiffness, yld.hardening, yld.yield_drift, yld.geometric, yld.limit)
    inputs = (*building, *units, *(springs or ()), *law, load_vec, monitors.rows, monitors.kind, monitors.record_coef)
    key = (dt, most_yielding, springs is None, yld is None, *(a.tobytes() for a in inputs))
    if key not in _MADE:
        if len(_MADE) >= _MADE_MAX:
            del _MADE[next(iter(_MADE))]
        _MADE[key] = _make_tables(building, units, springs, yld, load_vec, dt, monitors, most_yielding)
    return _MADE[key]


def _make_tables(building, units, springs, yld, load_vec, dt, monitors, most_yielding) -> ClearStep | None:
    storeys = 0 if yld is None else len(yld.stiffness)
    made = {}
    for count in range(_most_at_once(storeys, most_yielding) + 1):
        for yielding in combinations(range(storeys), count):
            tables = _pattern_tables(building, units, springs, yld, load_vec, dt, monitors, yielding)
            if tables is None and count == 0:
                return None
            if tables is not None:
                made[sum(1 << i for i in yielding)] = tables
    walled = np.flatnonzero(units.kind & UNIT_WALLS)
    stacked = [np.concatenate(parts) for parts in zip(*_same_modes_read(list(made.values())))]
    return ClearStep(np.array(list(made), dtype=np.int64), *stacked, 0.5 * units.gap[walled],
                     _twins(units, springs, len(building.mass)))


def _most_at_once(storeys: int, most_yielding: int) -> int:
    """The most storeys yielding at once that the tables are made for: up to most_yielding, while the patterns
    (every set of that many storeys or fewer) number at most MOST_PATTERNS."""
    most = 0
    while most < min(most_yielding, storeys) and sum(comb(storeys, c) for c in range(most + 2)) <= MOST_PATTERNS:
        most += 1
    return most


def _same_modes_read(patterns: list) -> list:
    """The patterns' tables with as many modes read in each (inv's rows, inv_size, bound's last columns), those
    they lack read as zero: a pair of overdamped modes is read twice, an oscillating pair once (_reach)."""
    most = max(tables[5].shape[0] for tables in patterns)
    padded = []
    for flow, work, visc, square, part, inv, inv_size, ends, bound, load in patterns:
        lack = most - inv.shape[0]
        padded.append((flow, work, visc, square, part, np.pad(inv, ((0, lack), (0, 0))), np.pad(inv_size, (0, lack)),
                       ends, np.pad(bound, ((0, 0), (0, lack))), load))
    return padded


def pattern(clear: ClearStep, index: int) -> ClearStep:
    """The tables of one pattern of clear (its index-th), each array its own rows."""
    count = len(clear.masks)
    return ClearStep(clear.masks[index : index + 1], *(a[index * (len(a) // count) : (index + 1) * (len(a) // count)]
                                                       for a in clear[1:-2]), clear.half, clear.twin)


def _pattern_tables(building, units, springs, yld, load_vec, dt, monitors, yielding) -> tuple | None:
    """One pattern's tables (ClearStep's fields from flow to load) with the storeys in `yielding` on a yielding
    branch and the others elastic; None where the pattern has no stable modes of its own.  Its rows: each
    monitor's, each monitor's slope, each band's (a walled unit's gap, then each storey's drift), each storey's
    drift velocity (its turn on a yielding branch)."""
    mass, stiffness, damping, flat = _free_configuration(building, units, springs, yld, yielding)
    flying = np.diag(stiffness) == 0.0  # a unit without a spring: no mode, its flight a polynomial
    if flat or np.any(flying & (np.diag(damping) != 0.0)):
        return None  # a perfectly plastic storey yielding: a zero mode, whose particular motion is not linear
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
    part, amplitudes, modes = _reach(mass, stiffness, damping, load_vec, offsets, flying, dt)
    walled = np.flatnonzero(units.kind & UNIT_WALLS)
    bands = np.zeros((len(walled) + offsets.shape[1], n))  # each walled unit's gap, then each storey's drift
    bands[np.arange(len(walled)), nf + walled] = 1.0
    bands[np.arange(len(walled)), units.floor[walled]] = -1.0
    for i in range(offsets.shape[1]):
        bands[len(walled) + i, i] = 1.0
        if i > 0:
            bands[len(walled) + i, i - 1] = -1.0
    drifts = bands[len(walled) :]
    rows = [_rows(generator, monitors.rows, monitors.kind, monitors.record_coef, modes),
            _rows(generator, monitors.rows, monitors.kind, monitors.record_coef, modes, slope=True),
            _rows(generator, bands, np.full(len(bands), MON_DISP), np.zeros(len(bands)), modes),
            _rows(generator, drifts, np.full(len(drifts), MON_DISP), np.zeros(len(drifts)), modes, slope=True)]
    return (flow, *forms, part, *amplitudes, *(np.concatenate(family) for family in zip(*rows)))


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


def _free_configuration(building, units, springs, yld, yielding=()):
    """M, K and C over the floors and the units, every unit free (a unit's spring and dashpot join it to its
    floor, segment.join) and the storeys in `yielding` on a yielding branch, the others elastic (K with P-delta's
    -P / h, segment.storey_stiffness, as a segment's configuration has it); and how many storeys that leaves without
    stiffness (perfectly plastic ones yielding without P-delta)."""
    nf = len(building.mass)
    n = nf + len(units.mass)
    stiffness = np.zeros((n, n))
    damping = np.zeros((n, n))
    stiffness[:nf, :nf] = building.stiffness
    damping[:nf, :nf] = building.damping
    flat = 0
    if yld is not None:
        branch = np.zeros_like(yld.branch)
        branch[list(yielding)] = 1
        flat = storey_stiffness(yld._replace(branch=branch), stiffness)
    if springs is not None:
        for j in range(len(units.mass)):
            join(stiffness, units.floor[j], nf + j, springs.stiffness[j])
            join(damping, units.floor[j], nf + j, springs.damping[j])
    return np.concatenate([building.mass, units.mass]), stiffness, damping, flat


def _twins(units, springs, nf: int) -> np.ndarray:
    """Per degree of freedom, the unit before it if it is the same unit (segment.same_unit: its twin, whose motion
    it copies to the bit while the two are in the same state, as the segment's rows do), else -1: a damper of
    several units moves as one."""
    twin = np.full(nf + len(units.mass), -1, dtype=np.int64)
    for j in range(1, len(units.mass)):
        if same_unit(units, springs, j - 1, j):
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
    offset ((2n, 2 + storeys), zero for the units without a spring); the rows that read the modal amplitudes of
    the rest of the state (one of each complex pair) and each row's size, sum |.| (what its rounding scales by);
    and the modes of every other degree of freedom as _rows reads them.  The particular motion is q_p = a0 + a1 t with K a1 = l f' and K a0 + C a1 = l f(0) + G p."""
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
    # a real state's amplitudes in a complex pair are conjugate: one of each pair is read, its weight doubled
    kept = kap.imag >= 0.0
    vinv = np.linalg.inv(vec)
    inv = np.zeros((np.count_nonzero(kept), 2 * n), dtype=complex)
    inv[:, np.concatenate([modal, n + modal])] = vinv[kept]
    growth = np.maximum(1.0, np.exp(kap.real * dt))
    amplitudes = (inv, np.abs(inv).sum(axis=1))
    return part, amplitudes, (modal, kap, vec, np.abs(vinv), growth, kept, np.where(flying, load_vec / mass, 0.0))


def _rows(generator, rows, kinds, record_coef, modes, slope=False):
    """Per row over q (a monitor of layout.MON_* kind, or a unit's gap): its value as a row over u (ends), two
    nonnegative rows bounding its second derivative over the step (bound): over |y| = |u - particular| (the
    amplitudes bounded by |V^-1| |y|; 2n columns) and, after them, over the modal amplitudes' moduli (_reach; one
    column per mode read), and what the units without a spring add to either per unit of max |f| over the step
    (load_bound).  slope: the same for the row's first derivative (its bound's load part per unit of |f'|)."""
    modal, kap, vec, vinv_abs, growth, kept, flight = modes
    size = generator.shape[0]
    n = rows.shape[1]
    states = np.concatenate([modal, n + modal])
    pairs = np.where(kap.imag > 0.0, 2.0, 1.0)  # a mode read for its conjugate too
    ends = np.zeros((len(kinds), size))
    bound = np.zeros((len(kinds), 2 * n + np.count_nonzero(kept)))
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
        bound[m, 2 * n :] = (pairs * weights)[kept]
    return ends, bound, load_bound


@njit(cache=True, inline="always")
def _forms(work, visc, square, base, u):
    """u^T Q u of the three symmetric forms of a step (the work, the dissipation, the roof's square), the rows of
    each from base on, in one pass.  Each is summed in the order it always was, so each keeps its bits: one pass
    lets the CPU overlap the three chains of dependent adds where a pass per form waited on each in turn (the
    forms took nearly half of a bare 3-storey building's clear step that way, 2026-12-01)."""
    acc_w = 0.0
    acc_v = 0.0
    acc_s = 0.0
    for i in range(u.shape[0]):
        ui = u[i]
        if ui != 0.0:
            row_w = 0.5 * work[base + i, i] * ui
            row_v = 0.5 * visc[base + i, i] * ui
            row_s = 0.5 * square[base + i, i] * ui
            for j in range(i + 1, u.shape[0]):
                uj = u[j]
                row_w += work[base + i, j] * uj
                row_v += visc[base + i, j] * uj
                row_s += square[base + i, j] * uj
            acc_w += ui * row_w
            acc_v += ui * row_v
            acc_s += ui * row_s
    return 2.0 * acc_w, 2.0 * acc_v, 2.0 * acc_s


@njit(cache=True, inline="always")
def _row_ends(ends, bound, m, u, nxt, reach_of, r0, r_end, tight):
    """Row m at the step's start and end, and its modes' bound on |h''| over the step; u: the step's start
    (q, q', f(0), f', p), nxt: its end's (q, q'), r_end: f at its end; reach_of: |y| and then the moduli of the
    modal amplitudes (_advance, _amplitudes), read by the bound's first columns, or with tight by its last."""
    n2 = nxt.shape[0]
    h0 = ends[m, n2] * r0
    h1 = ends[m, n2] * r_end
    for j in range(n2 + 1, u.shape[0]):  # the load's slope and the plastic offsets, constant over the step
        h0 += ends[m, j] * u[j]
        h1 += ends[m, j] * u[j]
    reach = 0.0
    for j in range(n2):
        h0 += ends[m, j] * u[j]
        h1 += ends[m, j] * nxt[j]
        if not tight:
            reach += bound[m, j] * reach_of[j]
    if tight:
        for k in range(n2, reach_of.shape[0]):
            reach += bound[m, k] * reach_of[k]
    return h0, h1, reach


@njit(cache=True, inline="always")
def _advance(flow, part, base, twin, u, nxt, y, reach_of):
    """The state at the step's end into nxt (a unit in its twin's state gets its twin's, to the bit), u less the
    particular motion into y and |y| with its rounding into reach_of[:2n]; flow and part: the pattern's, from row
    base on.  Returns the largest size of the terms y was the difference of (its rounding's scale)."""
    n2 = nxt.shape[0]
    n = n2 // 2
    largest = 0.0
    for i in range(n2):
        acc = 0.0
        for j in range(u.shape[0]):
            acc += flow[base + i, j] * u[j]
        nxt[i] = acc
        yi = u[i]
        size = abs(yi)
        for c in range(part.shape[1]):
            term = part[base + i, c] * u[n2 + c]
            yi -= term
            size += abs(term)
        y[i] = yi
        reach_of[i] = abs(yi) + _ROUNDING * size
        largest = max(largest, size)
    for i in range(n):
        k = twin[i]
        if k >= 0 and u[i] == u[k] and u[n + i] == u[n + k]:
            nxt[i] = nxt[k]
            nxt[n + i] = nxt[n + k]
    return largest


@njit(cache=True, inline="always")
def _amplitudes(inv, inv_size, base, y, largest, reach_of):
    """The moduli of y's modal amplitudes into reach_of[2n:], each with what y's rounding (_ROUNDING of its largest
    term) can add to it; inv, inv_size: the pattern's rows from row base on."""
    n2 = y.shape[0]
    rounding = _ROUNDING * largest
    for k in range(reach_of.shape[0] - n2):
        re = 0.0
        im = 0.0
        for j in range(n2):
            w = inv[base + k, j]
            re += w.real * y[j]
            im += w.imag * y[j]
        reach_of[n2 + k] = np.sqrt(re * re + im * im) + inv_size[base + k] * rounding


@njit(cache=True, inline="always")
def _pattern(masks, yld):
    """The index of the tables made for the storeys' branches now (every storey elastic: 0), -1 if none are."""
    mask = 0
    if yld is not None:
        for i in range(yld.branch.shape[0]):
            if yld.branch[i] != BRANCH_ELASTIC:
                mask |= 1 << i
    for k in range(masks.shape[0]):
        if masks[k] == mask:
            return k
    return -1


@njit(cache=True, inline="always")
def _bands(half, yld, u, lo, hi):
    """Each band row's ends: a walled unit's walls, then each storey's: an elastic one's d_y about its plastic
    offset, a yielding one's drift anywhere, both within the collapse limit; and each storey's slot in u (its
    offset, or a yielding one's -s d_y: its element's constant force over the step)."""
    walls = half.shape[0]
    for r in range(walls):
        lo[r] = -half[r]
        hi[r] = half[r]
    if yld is not None:
        n2 = u.shape[0] - 2 - yld.offset.shape[0]
        for i in range(yld.offset.shape[0]):
            if yld.branch[i] == BRANCH_ELASTIC:
                lo[walls + i] = max(yld.offset[i] - yld.yield_drift[i], -yld.limit[i])
                hi[walls + i] = min(yld.offset[i] + yld.yield_drift[i], yld.limit[i])
                u[n2 + 2 + i] = yld.offset[i]
            else:
                lo[walls + i] = -yld.limit[i]
                hi[walls + i] = yld.limit[i]
                u[n2 + 2 + i] = -yld.branch[i] * yld.yield_drift[i]


# _within_bands, _keep_yielding and _within_peaks are inlined: run_scene hands clear_steps its tables and scratch
# borrowed (bundles.borrowed), whose reference counts test a null pointer.  Handed owned arrays, inlined, they kept
# an atomic count on every step and took half of a bare building's clear steps (0.98 against 0.45 ms, 2026-12-01)
@njit(cache=True, inline="always")
def _within_bands(ends, bound, load, u, nxt, reach_of, step, lo, hi):
    """Whether every band row (the table's rows from step's first on) provably stays inside its band over the
    step, by the margin of the band and of the positions the row is the difference of; step: (the first row, f(0),
    f at the end, max |f|, the step's tau^2 / 8, whether the bounds read the modal amplitudes: _row_ends)."""
    base, r0, r_end, f_max, spread, tight = step
    n = nxt.shape[0] // 2
    for r in range(lo.shape[0]):
        if hi[r] - lo[r] == np.inf:
            continue  # a storey that neither yields nor collapses
        h0, h1, reach = _row_ends(ends, bound, base + r, u, nxt, reach_of, r0, r_end, tight)
        size = 0.0
        for j in range(n):
            size += abs(ends[base + r, j] * u[j])
        margin = WALL_MARGIN * (min(hi[r] - lo[r], 2.0 * (abs(h0) + abs(h1))) + size + abs(h1 - h0))
        bulge = (reach + load[base + r] * f_max) * spread + margin
        if max(h0, h1) + bulge >= hi[r] or min(h0, h1) - bulge <= lo[r]:
            return False
    return True


@njit(cache=True, inline="always")
def _keep_yielding(ends, bound, load, yld, u, nxt, reach_of, step):
    """Whether every yielding storey's drift velocity (the table's rows from step's first on) provably keeps the
    branch's sign over the step: it does not unload within it.  step: (the first row, f(0), f at the end, f', the
    step's tau^2 / 8, whether the bounds read the modal amplitudes)."""
    if yld is None:
        return True
    base, r0, r_end, slope, spread, tight = step
    n2 = nxt.shape[0]
    for i in range(yld.branch.shape[0]):
        sign = yld.branch[i]
        if sign == BRANCH_ELASTIC:
            continue
        d0, d1, reach = _row_ends(ends, bound, base + i, u, nxt, reach_of, r0, r_end, tight)
        size = 0.0
        for j in range(n2):
            size += abs(ends[base + i, j] * u[j])
        if min(sign * d0, sign * d1) - (reach + load[base + i] * abs(slope)) * spread <= WALL_MARGIN * size:
            return False
    return True


@njit(cache=True, inline="always")
def _within_peaks(ends, bound, load, u, nxt, reach_of, step, peak, cap, marks):
    """Whether every monitor (the table's rows from step's first on, their slopes' after them) provably stays
    within its running peak over the step or keeps its slope's sign (its new peak then at an end, written into
    marks: the value, then the time from the step's start, -1 where none); step: (the first row, f(0), f at the
    end, f', max |f|, tau, whether the bounds read the modal amplitudes)."""
    base, r0, r_end, slope, f_max, tau, tight = step
    nmon = peak.shape[0]
    spread = tau * tau / 8.0
    for m in range(nmon):
        marks[nmon + m] = -1.0
        if not peak[m] < cap[m]:
            continue  # not searched: a stroke at its wall, or a run not asked for it
        h0, h1, reach = _row_ends(ends, bound, base + m, u, nxt, reach_of, r0, r_end, tight)
        if max(abs(h0), abs(h1)) + (reach + load[base + m] * f_max) * spread <= peak[m] * (1.0 + PEAK_RTOL):
            continue
        # it may pass its peak: where its slope keeps its sign, its extremes are at the ends
        d0, d1, reach = _row_ends(ends, bound, base + nmon + m, u, nxt, reach_of, r0, r_end, tight)
        if d0 * d1 <= 0.0 or min(abs(d0), abs(d1)) <= (reach + load[base + nmon + m] * abs(slope)) * spread:
            return False
        if max(abs(h0), abs(h1)) > peak[m]:
            marks[m] = max(abs(h0), abs(h1))
            marks[nmon + m] = tau if abs(h1) >= abs(h0) else 0.0
    return True


@njit(cache=True)
def clear_steps(clear, scratch, state, peaks, load, times, building, units, springs, yld):
    """Whole record steps by the tables from t for as long as each is clear: whole, not cut by the window's start
    nor holding a sample, no unit reaching a wall, no storey the end of its band nor a yielding one turning, and
    every monitor either within its running peak or monotone over the step (its new peak then at an end); returns
    the time they reached, the state moved, the work and the dissipation booked in diag (a yielding storey's
    offset and plastic work in yld and diag), the roof's square in x2 where a step is in the window.  The tables
    are the pattern's of the storeys' branches now (none: no step).  Each step is proved with the bounds over |y|
    first, and only where they cannot prove it with those over the modal amplitudes, which cost more to read.
    load: (the run's parameters, the record); times: (t, the run's end, the window's start, the next sample's
    time); state: (q, v, diag); peaks: (each monitor's running peak, its time, its cap, the first monitor of the
    group sharing its running peak, its window square);
    scratch: (u, the next state, y = u less the particular motion, |y| and then its modal amplitudes' moduli, the
    monitors' new peaks and their times (_within_peaks), each band's lower and upper end); building, units, springs
    (None without), yld (None: elastic): the scene's, whose energy the largest-energy diagnostic reads.  The
    bundles are unpacked once: unpacked on every step, each of their arrays cost a reference count there."""
    masks, flow, work, visc, square, part, inv, inv_size, ends, bound, load_bound, half, twin = clear
    u, nxt, y, reach_of, marks, lo, hi = scratch
    q, v, diag = state
    peak, peak_t, cap, share, x2 = peaks
    t, t_end, t_square, t_sample = times
    p, record = load
    k = _pattern(masks, yld)
    if k < 0:
        return t
    nf = building.mass.shape[0]
    n = q.shape[0]
    size = u.shape[0]
    nmon = peak.shape[0]
    nband = lo.shape[0]
    nmodes = reach_of.shape[0] - 2 * n
    first = k * (ends.shape[0] // masks.shape[0])  # the pattern's rows: monitors, slopes, bands, turns
    yielding = k > 0
    _bands(half, yld, u, lo, hi)
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
        largest = _advance(flow, part, k * 2 * n, twin, u, nxt, y, reach_of)
        r_end = r0 + r1 * tau
        spread = tau * tau / 8.0
        f_max = max(abs(r0), abs(r_end))
        bands = (first + 2 * nmon, r0, r_end, f_max, spread)
        turns = (first + 2 * nmon + nband, r0, r_end, r1, spread)
        within = (first, r0, r_end, r1, f_max, tau)
        if not (_within_bands(ends, bound, load_bound, u, nxt, reach_of, (*bands, False), lo, hi)
                and (not yielding or _keep_yielding(ends, bound, load_bound, yld, u, nxt, reach_of, (*turns, False)))
                and _within_peaks(ends, bound, load_bound, u, nxt, reach_of, (*within, False), peak, cap, marks)):
            # the bounds over |y| could not prove it: those over the modal amplitudes, which take their reading
            _amplitudes(inv, inv_size, k * nmodes, y, largest, reach_of)
            if not (_within_bands(ends, bound, load_bound, u, nxt, reach_of, (*bands, True), lo, hi)
                    and (not yielding or _keep_yielding(ends, bound, load_bound, yld, u, nxt, reach_of,
                                                        (*turns, True)))
                    and _within_peaks(ends, bound, load_bound, u, nxt, reach_of, (*within, True), peak, cap, marks)):
                return t
        for m in range(nmon):
            if marks[nmon + m] >= 0.0 and marks[m] > peak[m]:  # a member of a shared group may top another's mark
                raise_peak(peak, peak_t, share, m, marks[m], t + marks[nmon + m])
        step_work, step_visc, step_square = _forms(work, visc, square, k * size, u)
        diag[D_WORK] += step_work
        diag[D_VISC] += step_visc
        if t_next > t_square:
            x2[0] += step_square
        for i in range(n):
            q[i] = nxt[i]
            v[i] = nxt[n + i]
        diag[D_SEGMENTS] += 1.0
        diag[D_CLEAR] += 1.0
        if yld is not None:
            plastic_flow(yld, q, diag)  # none on every storey elastic
        e_now = energy(building, units, springs, yld, nf, q, v)
        if yld is not None:
            e_now += storey_gravity(yld, q)  # as scene_loop.move_to_end counts the balance's scale
        diag[D_EMAX] = max(diag[D_EMAX], e_now)
        t = t_next
