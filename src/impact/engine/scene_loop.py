"""The loop of a scene run, as a sequence of named steps.

Each pass builds the segment of the current configuration, searches every
constraint's next event (certified), integrates the energy terms and the
monitors exactly over the segment, moves the state to the segment's end and
resolves the events found there (every row whose event falls at that instant).

Arrays travel in the named bundles of :mod:`impact.engine.bundles`; the steps
on every segment take one structref of them, SegmentWork (see that
module on why).  Optional parts arrive as their own arguments, None when
absent, and numba prunes them at compile time: `springs` (PID and TMD units),
`fric` (Coulomb friction under CID units), `harm` (a harmonic load),
`record` (a piecewise-linear load record) and `yld` (storeys that yield).

The events are the rows of one table of constraints (bundles.Events): each
damper unit's row (its walls, its slide on the floor, its release from a
wall), then each yielding storey's (its drift reaching the yield surface or
the collapse limit, its drift velocity turning on a yielding branch).  Every
row is searched on the same segment by the same certified search
(events.first_exit); the earliest event ends the segment, and every event at
that instant is applied.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact.engine.bundles import (
    Events,
    InstantScratch,
    Rows,
    RunState,
    Segment,
    SegmentWork,
    StepTables,
    Tables,
    Vectors,
    Workspace,
    borrowed,
)
from impact.engine.clear_step import clear_steps
from impact.engine.contact import (
    CONTACT_TOL,
    event_cap_reached,
    floor_decision,
    floor_mass,
    floor_row,
    hold,
    leave_wall,
    meet_wall,
    note_penetration,
    plastic_end,
    rebound,
    rebound_too_slow,
    record_impact,
    rest_on_floor,
    slide_with,
    slip,
    solve_impulses,
    start_slide,
    stays,
    stuck_row,
)
from impact.engine.events import PEAK_RTOL, first_exit, peak_abs, raise_peak, shift_row
from impact.engine.layout import (
    BRANCH_ELASTIC,
    D_CAP,
    D_COLLAPSE,
    D_E0,
    D_E1,
    D_EMAX,
    D_FRICTION,
    D_GRAZE,
    D_IMPACTS,
    D_IMPACTS_WIN,
    D_IMPLOSS,
    D_NREC,
    D_PEAK_GAVE_UP,
    D_PEN_EXCESS,
    D_SEGMENTS,
    D_SIMULTANEOUS,
    D_STEPS,
    D_STICKS,
    D_STOP_ELEMENT,
    D_STOP_EVENT,
    D_STOP_SIDE,
    D_STUCKTIME,
    D_TEND,
    D_VISC,
    D_WORK,
    D_YIELDS,
    EV_COLLAPSE,
    EV_FLOOR_EXIT,
    EV_NONE,
    EV_RELEASE,
    EV_SLIDE_STOP,
    EV_UNLOAD,
    EV_WALL,
    EV_YIELD,
    MODE_FLOOR,
    MODE_FREE,
    MODE_LOCKED,
    MODE_STUCK,
    NDIAG,
    NPOLY,
    P_FROM_ITSELF,
    P_OMEGA,
    P_PERIOD,
    P_PHI,
    P_REC_DT,
    P_T0,
    P_TEND,
    P_TWIN,
    P_VSTICK,
    P_WINDOW,
    UNIT_SPRING,
    UNIT_WALLS,
)
from impact.engine.modal import (
    amplitude_moduli,
    curvature_bound,
    end_values,
    halve,
    halve_from_start,
    integrate_modal,
    modal_slot,
    modal_tables,
    mode_weights,
    monitor_row,
    square_integral,
)
from impact.engine.sampler import row_roundoff, sample_segment
from impact.engine.segment import (
    SINGLE_COLUMNS,
    bound,
    bound_tab,
    build_segment,
    config_slot,
    deriv_at0,
    derivative_row,
    energy,
    flow_change,
    flow_tables,
    int_prod,
    int_prod_ramp,
    integral_tables,
    kappa_powers,
    plastic_flow,
    poly_at,
    ramp_tables,
    record_value,
    same_unit,
    scene_key,
    state_from_exp,
    storey_drift,
    storey_gravity,
    take_flow_state,
    whole_step,
)

_ROUND_TOL = 1e-13  # 450 eps: the round-off of a difference of rows, relative to their terms' size


@njit(cache=True)
def _difference_row(C, P, a, b, cs, ps):
    """Row a less row b into cs, ps (b < 0: the ground, nothing to take away): a unit's gap row (the unit less
    its floor) or a storey's drift row (its floor less the one below).  Returns the size of row b's terms at
    tau = 0 (|re| + |im| for each mode, within sqrt 2 of its modulus), on which the difference is rounded."""
    if b < 0:
        for k in range(C.shape[1]):
            cs[k] = C[a, k]
        for k in range(NPOLY):
            ps[k] = P[a, k]
        return 0.0
    size = abs(P[b, 0])
    for k in range(C.shape[1]):
        cb = C[b, k]
        cs[k] = C[a, k] - cb
        size += abs(cb.real) + abs(cb.imag)
    for k in range(NPOLY):
        ps[k] = P[a, k] - P[b, k]
    return size


@njit(cache=True)
def _contact_tol(gap, row_bound, floor_size):
    """A unit's contact tolerance: CONTACT_TOL of its gap row's terms and gap, but never below _ROUND_TOL of the
    unit's and its floor's own rows, since the gap row is their difference and is rounded on their size
    (a 1e-7 m gap on a floor moving 1e-2 m is resolved to 1e-18 m, not to round-off of 1e-7 m).  The unit's
    row is at most the floor's plus the gap row's, so the floor's size (from _difference_row) is all it needs."""
    return max(CONTACT_TOL * (row_bound + gap), _ROUND_TOL * (2.0 * floor_size + row_bound))


@njit(cache=True)
def _unit_level(j, units, springs, fric):
    """wp^2 d/2 - a_f: what the contact force must overcome to release a unit at its wall."""
    level = 0.0
    if springs is not None:
        if units.kind[j] & UNIT_SPRING:
            level += springs.stiffness[j] / units.mass[j] * 0.5 * units.gap[j]
    if fric is not None:
        level -= fric[j]
    return level


@njit(cache=True)
def _still_leaving(j, nf, units, mode, escape, q, v):
    """Unit j left a wall (escape) and, when the segment ended at another unit's event, is still on it to
    round-off of its gap and not moving back: it keeps leaving (a search from the wall without its escape
    would find the touch it is leaving, and two units on opposite walls would trade it forever)."""
    if escape[j] == 0 or mode[j] != MODE_FREE:
        return False
    f = units.floor[j]
    half = 0.5 * units.gap[j]
    # to the contact tolerance of the gap and of the positions it is the difference of
    on_wall = abs(q[nf + j] - q[f] - escape[j] * half) <= CONTACT_TOL * (units.gap[j] + abs(q[nf + j]) + abs(q[f]))
    return on_wall and escape[j] * (v[nf + j] - v[f]) <= 0.0


@njit(cache=True)
def _all_free(mode, escape):
    """Every unit free and none leaving a wall: the configuration clear_step's tables are made for."""
    for j in range(mode.shape[0]):
        if mode[j] != MODE_FREE or escape[j] != 0:
            return False
    return True


@njit(cache=True)
def _storeys_settled(yld):
    """No storey leaving its yield surface or its turning point (an elastic building's always): the state
    clear_step's tables start from, on whichever branches."""
    if yld is not None:
        for i in range(yld.branch.shape[0]):
            if yld.escape[i] != 0 or yld.escape_v[i] != 0:
                return False
    return True


@njit(cache=True)
def _same_unit_state(j, nf, units, springs, w):
    mode, side, sigma, escape, escape_v, C, P = w.mode, w.side, w.sigma, w.escape, w.escape_v, w.C, w.P
    i = j - 1
    if not same_unit(units, springs, i, j):
        return False
    if mode[i] != mode[j] or side[i] != side[j] or sigma[i] != sigma[j] or escape[i] != escape[j] \
            or escape_v[i] != escape_v[j]:
        return False
    for k in range(P.shape[1]):
        if P[nf + i, k] != P[nf + j, k]:
            return False
    for k in range(C.shape[1]):
        if C[nf + i, k] != C[nf + j, k]:
            return False
    return True


@njit(cache=True)
def _clear_of_walls(kpow, ek, c, p, lo, hi, big_t, delta):
    """Certified: h stays inside (lo, hi) over [0, T] and ends farther than delta from both walls.

    The first step of first_exit over the whole segment, with h(T) from ek = exp(kap T): most sample
    steps of a record are settled by it without evaluating an exponential.
    """
    h0 = p[0]
    h1 = poly_at(p, big_t)
    for k in range(c.shape[0]):
        ck = c[k]
        if ck.real != 0.0 or ck.imag != 0.0:
            h0 += ck.real
            h1 += (ck * ek[k]).real
    spread = bound_tab(kpow, c, p, 2, big_t) * big_t * big_t / 8.0
    return (max(h0, h1) + spread < hi and min(h0, h1) - spread > lo
            and hi - h1 >= delta and h1 - lo >= delta)


SIDE_FOUND, SIDE_KEPT = 2, 3  # _earliest: the end of the band the search crossed, or the row's entry untouched


@njit(cache=True)
def _earliest(out, best, ties, r, kind, side, ev_t, ev_side, ev_kind):
    """Row r's event found by a search (out) becomes its event if it comes first (or ties, with ties); returns the
    earliest time so far.  side: the event's side (SIDE_FOUND: the end of the band the search crossed, SIDE_KEPT:
    the row's entry left as it is, else this side)."""
    if out[0] < best or (ties and out[0] == best):
        ev_t[r] = out[0]
        if side == SIDE_FOUND:
            ev_side[r] = int(out[1])
        elif side != SIDE_KEPT:
            ev_side[r] = side
        ev_kind[r] = kind
        return out[0]
    return best


@njit(cache=True)
def _band_exit(w, lo, hi, size, escape, horizon, ek_tau):
    """The certified first exit before `horizon` of the halved row in w.cs, w.ps from the band (lo, hi), into
    w.found; `size` is what the row was rounded on (_difference_row).  When ek_tau is the horizon, a row clear of
    both ends over the whole segment is settled without a search (_clear_of_walls)."""
    kpow, cs, ps, out = w.kpow, w.cs, w.ps, w.found
    delta = _contact_tol(hi - lo, bound_tab(kpow, cs, ps, 0, 0.0), size)
    if escape == 0 and horizon == ek_tau and _clear_of_walls(kpow, w.ek, cs, ps, lo, hi, horizon, delta):
        _cleared(out)
    else:
        first_exit(w.kap, kpow, cs, ps, lo, hi, horizon, escape, delta, out)


@njit(cache=True)
def _cleared(out):
    """A search's output for a row _clear_of_walls settles: no event, one step."""
    out[0] = np.inf
    out[1] = 0.0
    out[2] = 0.0
    out[3] = 1.0


#: the margin of a storey cleared from its reach (_storey_clear, _turning_clear), relative to the terms its row is
#: made of: far above their round-off (a few eps), so that a storey cleared so is one its row's own test
#: (_clear_of_walls, or first_exit's first step) clears too, and the run is the same to the bit
_REACH_TOL = 1e-8


@njit(cache=True)
def _modal_reach(w, s, i, d):
    """Storey i's drift row in slot s from its reach (modal.storey_reach), without building it: with a_k = |d_k w_k|
    (d_k: the storey's drift in mode k, w_k: the segment's modal amplitude), the sums of a_k |kap_k|^n for n = d,
    d + 1, d + 2, and the size of the two floors' terms of the d-th derivative, which the row is rounded on."""
    aw, kpow, reach = w.aw, w.kpow, w.reach
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    size = 0.0
    for k in range(2 * w.size[s]):
        a = reach[s, i, 0, k] * aw[k]
        s0 += a * kpow[d, k]
        s1 += a * kpow[d + 1, k]
        s2 += a * kpow[d + 2, k]
        size += reach[s, i, 1, k] * aw[k] * kpow[d, k]
    return s0, s1, s2, size


@njit(cache=True)
def _storey_poly(P, i):
    """The drift row's polynomial terms of tau^2 and tau^3 (a zero mode's particular solution)."""
    if i == 0:
        return P[0, 2], P[0, 3]
    return P[i, 2] - P[i - 1, 2], P[i, 3] - P[i - 1, 3]


@njit(cache=True)
def _storey_clear(w, s, i, lo, hi, big_t):
    """Whether storey i's drift stays inside (lo, hi) over [0, T], farther from both ends than its row's round-off,
    certified from the state and the slot's reach without building the row.

    The drift starts at u0 with velocity du0, and its second derivative is at most m2 (the modes' sum of
    |d_k w_k| |kap_k|^2 and the polynomial's), so over [0, T] it stays within m2 T^2 / 2 of u0 + du0 t.  The row's
    own test adds its spread, m2 T^2 / 8 over the half row (equal to m2's to the basis' round-off, taken 4 % wider
    here); first_exit's first step over a row cleared so spans the whole segment."""
    q = w.q
    u0 = storey_drift(q, i)
    du0 = storey_drift(w.v, i)
    p2, p3 = _storey_poly(w.P, i)
    terms, _, m2, size = _modal_reach(w, s, i, 0)
    m2 += 2.0 * abs(p2) + 6.0 * big_t * abs(p3)
    curve = m2 * big_t * big_t * 0.63
    below = abs(q[i - 1]) if i > 0 else 0.0
    slack = _REACH_TOL * (terms + size + abs(q[i]) + below + hi - lo)
    end = u0 + du0 * big_t
    return max(u0, end) + curve + slack < hi and min(u0, end) - curve - slack > lo


@njit(cache=True)
def _turning_clear(w, s, i, sign, big_t):
    """Whether yielding storey i's drift velocity keeps its branch's sign over [0, T], farther from zero than its
    row's round-off, certified from the state and the slot's reach without building the row: it starts at
    sign du0 and moves by at most m2 T (m2: its derivative's bound, _storey_clear's), and the velocity row's own
    test adds its spread, m3 T^2 / 8 (taken 4 % wider)."""
    v = w.v
    du0 = sign * storey_drift(v, i)
    p2, p3 = _storey_poly(w.P, i)
    terms, m2, m3, size = _modal_reach(w, s, i, 1)
    m2 += 2.0 * abs(p2) + 6.0 * big_t * abs(p3)
    m3 += 6.0 * abs(p3)
    below = abs(v[i - 1]) if i > 0 else 0.0
    slack = _REACH_TOL * (terms + size + abs(v[i]) + below)
    return du0 - m2 * big_t - 0.13 * m3 * big_t * big_t - slack > 0.0


@njit(cache=True)
def _sign_exit(w, sign, escape_v, horizon, ek_tau, may_clear):
    """Where the halved row in w.cs, w.ps stops moving in the direction `sign` (sign row' >= 0 while it keeps
    on): the certified first exit of sign row' from [0, inf) before `horizon`, into w.found (the velocity row
    left in w.cq, w.pq).  With may_clear, settled without a search where it is clear (as _band_exit)."""
    kap, kpow, cq, pq, out = w.kap, w.kpow, w.cq, w.pq, w.found
    derivative_row(kap, w.cs, w.ps, cq, pq)
    for k in range(kap.shape[0]):
        cq[k] = sign * cq[k]
    for k in range(NPOLY):
        pq[k] = sign * pq[k]
    dv = CONTACT_TOL * bound_tab(kpow, cq, pq, 0, 0.0)
    if may_clear and escape_v == 0 and horizon == ek_tau and _clear_of_walls(kpow, w.ek, cq, pq, 0.0, np.inf,
                                                                             horizon, dv):
        out[0] = np.inf
        out[2] = 0.0
        out[3] = 1.0
    else:
        first_exit(kap, kpow, cq, pq, 0.0, np.inf, horizon, escape_v, dv, out)


@njit(cache=True)
def _book_search(diag, out):
    diag[D_GRAZE] += out[2]
    diag[D_STEPS] += out[3]


@njit(cache=True)
def search_constraints(w, s, units, springs, fric, yld, tau_max, ramp, ek_tau, harmonic):
    """The next event of every row of the constraint table (bundles.Events: the damper units' rows first, a
    yielding building's storeys' after them), each row searched up to the earliest event found so far; returns
    the earliest (inf if none up to tau_max).  s: the segment's configuration slot; ramp: (r0, r1), the record's
    value at the segment's start and its slope; harmonic: whether the load is harmonic.

    ek = exp(kap ek_tau): when ek_tau is the horizon, a row far from its band's ends is cleared without a search.
    The searched rows are weighted half rows (modal.halve): half the exponentials per evaluation.
    """
    ev_t = w.ev_t
    nu = units.mass.shape[0]
    nf = w.C.shape[0] - nu
    r0, r1 = ramp
    best = tau_max
    for j in range(nu):
        best = _search_unit(w, nf, j, units, springs, fric, r0, r1, best, ek_tau)
    if yld is not None:
        law = borrowed(yld)  # bound to each storey's step: borrowed, its arrays count no references
        for i in range(law.branch.shape[0]):
            best = _search_storey(w, s, law, i, nu + i, best, ek_tau, harmonic)
    found = np.inf
    for r in range(ev_t.shape[0]):
        if ev_t[r] < found:
            found = ev_t[r]
    return found


@njit(cache=True)
def _search_unit(w, nf, j, units, springs, fric, r0, r1, best, ek_tau):
    """Unit j's row in its contact mode: a free unit's gap within its walls (and a sliding unit's slide keeping
    its direction), a unit held on a wall by a contact force that pushes, a unit friction holds on its floor by a
    force friction can give.  Returns the earliest event time so far."""
    kap, C, P, kpow, wt, diag = w.kap, w.C, w.P, w.kpow, w.wt, w.diag
    mode, side, sigma, escape, escape_v = w.mode, w.side, w.sigma, w.escape, w.escape_v
    ev_t, ev_side, ev_kind, cs, ps, cq, pq, out = w.ev_t, w.ev_side, w.ev_kind, w.cs, w.ps, w.cq, w.pq, w.found
    ev_t[j] = np.inf
    ev_kind[j] = EV_NONE
    if not units.kind[j] & UNIT_WALLS or mode[j] == MODE_LOCKED:
        return best
    if j > 0 and _same_unit_state(j, nf, units, springs, w):
        # identical to the unit before (a multi-unit damper moving as one): the same event, bit for bit
        ev_t[j] = ev_t[j - 1]
        ev_side[j] = ev_side[j - 1]
        ev_kind[j] = ev_kind[j - 1]
        return best
    f = units.floor[j]
    if mode[j] == MODE_FREE:
        half = 0.5 * units.gap[j]
        size = _difference_row(C, P, nf + j, f, cs, ps)
        halve_from_start(kap, cs, ps, wt)
        _band_exit(w, -half, half, size, escape[j], best, ek_tau)
        _book_search(diag, out)
        best = _earliest(out, best, True, j, EV_WALL, SIDE_FOUND, ev_t, ev_side, ev_kind)
        if fric is not None:
            if fric[j] > 0.0:
                # sigma s' > 0 while sliding; the slide ends where it reaches 0
                _sign_exit(w, sigma[j], escape_v[j], best, ek_tau, False)
                diag[D_STEPS] += out[3]
                best = _earliest(out, best, False, j, EV_SLIDE_STOP, 0, ev_t, ev_side, ev_kind)
    elif mode[j] == MODE_STUCK:
        stuck_row(kap, C, P, f, side[j], units.load[j] * r0, units.load[j] * r1,
                  _unit_level(j, units, springs, fric), cq, pq)
        halve_from_start(kap, cq, pq, wt)
        delta = CONTACT_TOL * bound_tab(kpow, cq, pq, 0, 0.0)
        q0 = deriv_at0(kap, cq, pq, 0)
        esc = 1 if -q0 < delta else 0
        first_exit(kap, kpow, cq, pq, -np.inf, 0.0, best, esc, delta, out)
        _book_search(diag, out)
        best = _earliest(out, best, True, j, EV_RELEASE, SIDE_KEPT, ev_t, ev_side, ev_kind)
    elif mode[j] == MODE_FLOOR:
        if fric is not None:
            a_f = fric[j]
            floor_row(kap, C, P, f, units.load[j] * r0, units.load[j] * r1, cq, pq)
            halve_from_start(kap, cq, pq, wt)
            delta = CONTACT_TOL * (bound_tab(kpow, cq, pq, 0, 0.0) + a_f)
            q0 = deriv_at0(kap, cq, pq, 0)
            esc = 0
            if a_f - abs(q0) < delta:
                esc = 1 if q0 > 0.0 else -1
            first_exit(kap, kpow, cq, pq, -a_f, a_f, best, esc, delta, out)
            diag[D_STEPS] += out[3]
            best = _earliest(out, best, True, j, EV_FLOOR_EXIT, SIDE_FOUND, ev_t, ev_side, ev_kind)
    return best


@njit(cache=True)
def _search_storey(w, s, yld, i, r, best, ek_tau, harmonic):
    """Storey i's row (row r of the table) on its branch: an elastic storey's drift u stays within d_y of its
    plastic offset p (and within the collapse limit); a yielding one's drift velocity keeps the branch's sign
    (sign u' >= 0) and its drift stays within the collapse limit.  Returns the earliest event time so far.

    A storey far from both ends of its band is cleared from its state and its slot s's reach before its row is
    built (_storey_clear, _turning_clear): most of a record's sample steps."""
    w.ev_t[r] = np.inf
    w.ev_kind[r] = EV_NONE
    if yld.branch[i] != BRANCH_ELASTIC:
        return _search_yielding_storey(w, s, yld, i, r, best, ek_tau, harmonic)
    out = w.found
    lim = yld.limit[i]
    lo = max(yld.offset[i] - yld.yield_drift[i], -lim)
    hi = min(yld.offset[i] + yld.yield_drift[i], lim)
    if hi - lo == np.inf:
        return best
    if yld.escape[i] == 0 and best == ek_tau and not harmonic and _storey_clear(w, s, i, lo, hi, best):
        _cleared(out)  # as _band_exit's own shortcut would settle it
        _book_search(w.diag, out)
        return best
    _band_exit(w, lo, hi, _storey_row(w, i), yld.escape[i], best, ek_tau)
    _book_search(w.diag, out)
    side = 1 if out[1] > 0.0 else -1
    at_limit = hi == lim if side > 0 else lo == -lim
    return _earliest(out, best, True, r, EV_COLLAPSE if at_limit else EV_YIELD, side, w.ev_t, w.ev_side, w.ev_kind)


@njit(cache=True)
def _search_yielding_storey(w, s, yld, i, r, best, ek_tau, harmonic):
    """A yielding storey's row: its drift velocity keeps the branch's sign, its drift stays within the collapse
    limit.  Each is cleared from the storey's reach first (_turning_clear, _storey_clear), and the row is built
    only for what that leaves to search."""
    out, ev_t, ev_kind, ev_side = w.found, w.ev_t, w.ev_kind, w.ev_side
    lim = yld.limit[i]
    sign = yld.branch[i]
    size = -1.0  # the row not built
    if yld.escape_v[i] == 0 and best == ek_tau and not harmonic and _turning_clear(w, s, i, sign, best):
        _cleared(out)  # as _sign_exit's own shortcut would settle it
    else:
        size = _storey_row(w, i)
        _sign_exit(w, sign, yld.escape_v[i], best, ek_tau, True)
    _book_search(w.diag, out)
    best = _earliest(out, best, True, r, EV_UNLOAD, sign, ev_t, ev_side, ev_kind)
    if lim < np.inf:
        if not harmonic and _storey_clear(w, s, i, -lim, lim, best):
            _cleared(out)  # as first_exit settles it: in one step over the whole segment
        else:
            if size < 0.0:
                size = _storey_row(w, i)
            _band_exit(w, -lim, lim, size, 0, best, -1.0)
        _book_search(w.diag, out)
        best = _earliest(out, best, True, r, EV_COLLAPSE, 1 if out[1] > 0.0 else -1, ev_t, ev_side, ev_kind)
    return best


@njit(cache=True)
def _storey_row(w, i):
    """Storey i's drift row, halved, into w.cs, w.ps; returns the size it was rounded on (_difference_row)."""
    size = _difference_row(w.C, w.P, i, i - 1, w.cs, w.ps)
    halve_from_start(w.kap, w.cs, w.ps, w.wt)
    return size


@njit(cache=True)
def at_instant(tau_ev):
    """The latest event time that still falls at the instant tau_ev (to 16 ulps)."""
    return tau_ev * (1.0 + 16.0 * 2.220446049250313e-16) + 1e-300


@njit(cache=True)
def name_stop(tau_ev, events, nu, diag):
    """Which element's event a run stopped at (layout.D_STOP_*): the first row of the constraint table with an
    event at the instant tau_ev; its element is a unit or, past the units' rows, a storey (its kind of event
    tells which)."""
    limit = at_instant(tau_ev)
    for r in range(events.t.shape[0]):
        if events.t[r] <= limit:
            _stop_at(r if r < nu else r - nu, events.kind[r], events.side[r], diag)
            return


@njit(cache=True)
def _stop_at(element, kind, side, diag):
    diag[D_STOP_ELEMENT] = element
    diag[D_STOP_EVENT] = kind
    diag[D_STOP_SIDE] = side


@njit(cache=True)
def resolve_storeys(tau_ev, yld, events, nu, q, v, diag):
    """Apply every storey's event at this instant (tau_ev into the segment; storey i's is row nu + i of the
    constraint table): a storey reaching its yield surface moving outward yields (its offset set so that u - p is
    exactly s d_y); a yielding storey whose drift turns unloads elastically from the surface; a drift at the
    collapse limit ends the run (diag[D_COLLAPSE])."""
    branch, dy, offset, escape = yld.branch, yld.yield_drift, yld.offset, yld.escape
    limit = at_instant(tau_ev)
    for i in range(branch.shape[0]):
        if not events.t[nu + i] <= limit:
            continue
        kind = events.kind[nu + i]
        side = events.side[nu + i]
        u = storey_drift(q, i)
        if kind == EV_COLLAPSE:
            diag[D_COLLAPSE] = 1.0
        elif kind == EV_YIELD:
            if side * storey_drift(v, i) > 0.0:
                branch[i] = side
                offset[i] = u - side * dy[i]
                yld.yields[i] += 1
                diag[D_YIELDS] += 1.0
            else:
                escape[i] = side  # a touch of the surface while turning back: it stays elastic and leaves it
        elif kind == EV_UNLOAD:
            _unload(yld, i, u)


@njit(cache=True)
def _unload(yld, i, u):
    side = yld.branch[i]
    yld.branch[i] = BRANCH_ELASTIC
    yld.offset[i] = u - side * yld.yield_drift[i]
    yld.escape[i] = side


@njit(cache=True)
def storey_jumps(yld, q, v, diag, impulses):
    """After an instant's events, whose impulses and plastic merges may have made the floors' velocities jump: a
    yielding storey now moving inward unloads; and, after impacts (impulses), an elastic storey on its yield
    surface now moving outward yields.  Not without impacts: a storey that has just unloaded sits on its surface
    with a drift velocity of round-off size, whose sign would make it yield and unload again for ever."""
    branch, dy, offset = yld.branch, yld.yield_drift, yld.offset
    for i in range(branch.shape[0]):
        u = storey_drift(q, i)
        du = storey_drift(v, i)
        if branch[i] != BRANCH_ELASTIC:
            if branch[i] * du < 0.0:
                _unload(yld, i, u)
        elif impulses and yld.escape[i] != 0 and yld.escape[i] * du > 0.0 and _on_surface(yld, i, q):
            side = yld.escape[i]
            branch[i] = side
            offset[i] = u - side * dy[i]
            yld.escape[i] = 0
            yld.yields[i] += 1
            diag[D_YIELDS] += 1.0


@njit(cache=True)
def _on_surface(yld, i, q):
    """Storey i's elastic drift on the yield surface it left (yld.escape), to the contact tolerance of its floors."""
    u = storey_drift(q, i)
    lower = abs(q[i - 1]) if i > 0 else 0.0
    return abs(u - yld.offset[i] - yld.escape[i] * yld.yield_drift[i]) <= CONTACT_TOL * (yld.yield_drift[i] + abs(q[i])
                                                                                    + lower)


@njit(cache=True)
def storeys_after_segment(yld, q, v):
    """A storey that left its yield surface keeps its escape only while it is still on it and not moving back out
    (as a unit leaving a wall, _still_leaving); the drift-velocity searches start afresh."""
    escape, escape_v = yld.escape, yld.escape_v
    for i in range(escape.shape[0]):
        if escape[i] != 0 and not (_on_surface(yld, i, q) and escape[i] * storey_drift(v, i) <= 0.0):
            escape[i] = 0
        escape_v[i] = 0


@njit(cache=True)
def growth_rate(cache, s):
    """The largest Re kap of slot s's modes when one grows (a storey whose P-delta outweighs its stiffness), else 0:
    the run keeps such a segment within 1 / rate, over which every exponential stays within e of its start."""
    rate = 0.0
    for k in range(2 * cache.size[s]):
        rate = max(rate, cache.lam[s, k].real)
    return rate


@njit(cache=True)
def grow_powers(kap, kpow):
    """|kap|^n times e for a growing mode: bound_tab's bounds over a segment within 1 / growth_rate."""
    for k in range(kap.shape[0]):
        if kap[k].real > 0.0:
            for n in range(kpow.shape[0]):
                kpow[n, k] *= math.e


@njit(cache=True)
def integrate_segment(w, tau, building, units, springs, harm, record, load_at):
    """Exact work of the load, viscous dissipation and stuck time over [0, tau] (tables: integral_tables);
    load_at: (theta0, r0, r1), the load at the segment's start (segment_load).  Without a harmonic load the
    load's work and the dissipation's products of velocity rows are taken in the ramp form (segment.ramp_tables),
    from the state's velocities."""
    kap, C, P, mode, load_vec, pair, single, diag = w.kap, w.C, w.P, w.mode, w.load_vec, w.pair, w.single, w.diag
    ramp, v = w.ramp, w.v
    cv, pv, cu, pu = w.cv, w.pv, w.cu, w.pu
    theta0, r0, r1 = load_at
    nf = building.mass.shape[0]
    nt = kap.shape[0]
    nfull = C.shape[0]
    cb = building.damping
    # velocity rows of every degree of freedom
    for i in range(nfull):
        derivative_row(kap, C[i], P[i], cv[i], pv[i])
    # work: the load f(tau) times sum_i load_vec_i v_i
    for k in range(nt):
        cu[0, k] = 0.0
    for k in range(NPOLY):
        pu[0, k] = 0.0
    for i in range(nfull):
        li = load_vec[i]
        if li != 0.0:
            for k in range(nt):
                cu[0, k] += li * cv[i, k]
            for k in range(NPOLY):
                pu[0, k] += li * pv[i, k]
    for k in range(nt):
        cu[1, k] = 0.0
    for k in range(NPOLY):
        pu[1, k] = 0.0
    if harm is not None:
        cu[1, nt - 2] = np.exp(1j * theta0) / 2j
        cu[1, nt - 1] = cu[1, nt - 2].conjugate()
    if record is not None:
        pu[1, 0] = r0
        pu[1, 1] = r1
    if harm is None:
        # in the ramp form, from the state's velocities, as the dissipation below (only a yielding building's
        # segments come here under a record: integrate_modal's from_state)
        lv0 = 0.0
        for i in range(nfull):
            lv0 += load_vec[i] * v[i]
        diag[D_WORK] += int_prod_ramp(tau, ramp, single, lv0, cu[0], pu[0], r0, cu[1], pu[1])
    else:
        diag[D_WORK] += int_prod(tau, pair, single, cu[0], pu[0], cu[1], pu[1])
    # viscous dissipation: the building's damping, then the units' dashpots
    visc = 0.0
    for a in range(nf):
        for k in range(nt):
            cu[0, k] = 0.0
        for k in range(NPOLY):
            pu[0, k] = 0.0
        for b in range(nf):
            cab = cb[a, b]
            if cab != 0.0:
                for k in range(nt):
                    cu[0, k] += cab * cv[b, k]
                for k in range(NPOLY):
                    pu[0, k] += cab * pv[b, k]
        if harm is not None:
            visc += int_prod(tau, pair, single, cv[a], pv[a], cu[0], pu[0])
        else:
            visc += int_prod_ramp(tau, ramp, single, v[a], cv[a], pv[a], damped_start(cb, v, a), cu[0], pu[0])
    if springs is not None:
        uc = springs.damping
        ufloor = units.floor
        for j in range(uc.shape[0]):
            if uc[j] != 0.0 and mode[j] == MODE_FREE:
                f = ufloor[j]
                for k in range(nt):
                    cu[0, k] = cv[nf + j, k] - cv[f, k]
                for k in range(NPOLY):
                    pu[0, k] = pv[nf + j, k] - pv[f, k]
                if harm is not None:
                    visc += uc[j] * int_prod(tau, pair, single, cu[0], pu[0], cu[0], pu[0])
                else:
                    rel = v[nf + j] - v[f]
                    visc += uc[j] * int_prod_ramp(tau, ramp, single, rel, cu[0], pu[0], rel, cu[0], pu[0])
    diag[D_VISC] += visc
    for j in range(mode.shape[0]):
        if mode[j] != MODE_FREE and mode[j] != MODE_LOCKED:
            diag[D_STUCKTIME] += tau


@njit(cache=True)
def damped_start(cb, v, a):
    """Row a of the damping matrix times the velocities: the damping force's start value."""
    out = 0.0
    for b in range(cb.shape[1]):
        out += cb[a, b] * v[b]
    return out


@njit(cache=True)
def step_tables(s, key, tau, dt, kap, ek, pair, single, ramp, dtab):
    """ek = exp(kap tau) and the integral tables over tau.

    A record's whole sample step (tau == dt) recurs in every configuration
    after each event: its tables are kept per cache slot and copied, the ramp form's with them (any other step's
    are made in the loop, once a segment's step is known, for the step it integrates).
    """
    dkey, dek, dpair, dsingle, dramp = dtab
    nt = kap.shape[0]
    if tau != dt:
        for k in range(nt):
            ek[k] = np.exp(kap[k] * tau)
        integral_tables(kap, ek, tau, pair, single)
        return
    if dkey[s] != key:
        for k in range(nt):
            dek[s, k] = np.exp(kap[k] * tau)
        integral_tables(kap, dek[s], tau, dpair[s], dsingle[s])
        ramp_tables(kap, dek[s], tau, dramp[s], dsingle[s])
        flow_tables(kap, dek[s], tau, dsingle[s])
        dkey[s] = key
    for k in range(nt):
        ek[k] = dek[s, k]
        for m in range(SINGLE_COLUMNS):
            single[k, m] = dsingle[s, k, m]
        for l in range(nt):
            pair[k, l] = dpair[s, k, l]
            ramp[k, l] = dramp[s, k, l]


@njit(cache=True)
def monitor_modal(w, s, n, tau, t, t_win, monitors, ramp, harmonic, yielding):
    """Certified peaks of every monitor over the segment, and the roof's square integrated over the window from
    t_win (inf: a run whose window no one reads); ramp: (r0, r1), the record's value at the segment's start and
    its slope.

    Rows and curvature bounds come from the modal tables: a segment whose ends
    and bound cannot beat the running peak is settled without the search, as
    peak_abs's own first test would settle it.  A monitor whose peak has
    reached its cap is not searched again: a stroke at its wall, or a monitor
    the run was not asked to certify (cap 0, scenes.PEAK_GROUPS); the first
    (the roof) still gives the window its square where the segment reaches into it.
    """
    kap, kpow, ek, cm, pm, stack, wt, diag = w.kap, w.kpow, w.ek, w.cm, w.pm, w.stack, w.wt, w.diag
    mon_peak, mon_peak_t, mon_roundoff = w.mon_peak, w.mon_peak_t, w.mon_roundoff
    mon_rows, mon_cap, share = monitors.rows, monitors.cap, monitors.share
    r0, r1 = ramp
    for m in range(mon_rows.shape[0]):
        searched = mon_peak[m] < mon_cap[m]
        squared = m == 0 and t + tau > t_win
        if not searched and not squared:
            continue
        monitor_row(w, s, m, n, monitors, r0, r1, harmonic)
        if squared:
            window_square(w, tau, t, t_win, yielding)
        if not searched:
            continue
        halve(cm, wt)
        h0, h1 = end_values(ek, cm, pm, tau)
        ends = max(abs(h0), abs(h1))
        peak = mon_peak[m]
        if ends >= mon_cap[m] * (1.0 - PEAK_RTOL):
            # a stroke at its wall at an end of the segment: the wall bounds it over the segment (a unit through
            # its wall is measured apart, as penetration), so that end is its peak, without a search that its
            # row's cancelling terms could keep from settling (a unit resting at its wall as a record starts)
            if ends > peak:
                raise_peak(mon_peak, mon_peak_t, share, m, ends, t + (tau if abs(h1) >= abs(h0) else 0.0))
            continue
        if ends > peak or ends + curvature_bound(w, s, m, n, tau, harmonic) * tau * tau / 8.0 \
                > peak * (1.0 + PEAK_RTOL):
            peak, at, certified, slack = peak_abs(kap, kpow, ek, cm, pm, tau, peak, stack)
            if not certified:
                diag[D_PEAK_GAVE_UP] += 1.0
            mon_roundoff[m] = max(mon_roundoff[m], slack)
            if at >= 0.0:
                raise_peak(mon_peak, mon_peak_t, share, m, peak, t + at)


@njit(cache=True)
def window_square(w, tau, t, t_win, yielding):
    """The first monitor's (the roof's) square integrated over the part of the segment inside the window.

    On a yielding building the sum over the modes is taken in full, not halved over conjugate pairs: beside a
    storey whose post-yield stiffness b k - P/h is near zero a slow pair's coefficients are kilometres that cancel
    to the roof's millimetres, and they are conjugates only to round-off of that size, which the halved sum
    squares into the integral (probe scene 2572387895-2905: -0.38 m^2 s for a roof peak of 0.045 m)."""
    kap, cm, pm, pair, single, cs, ps, wt, mon_x2 = w.kap, w.cm, w.pm, w.pair, w.single, w.cs, w.ps, w.wt, w.mon_x2
    start = max(t_win - t, 0.0)
    if start > 0.0:
        # the one segment that the window's start cuts: tables of its own
        shift_row(kap, cm, pm, start, cs, ps)
        rest = tau - start
        ek_w = np.exp(kap * rest)
        pair_w = np.empty_like(pair)
        single_w = np.empty_like(single)
        integral_tables(kap, ek_w, rest, pair_w, single_w)
        mon_x2[0] += int_prod(rest, pair_w, single_w, cs, ps, cs, ps)
    elif yielding:
        mon_x2[0] += int_prod(tau, pair, single, cm, pm, cm, pm)
    else:
        mon_x2[0] += square_integral(cm, pm, wt, pair, single, tau)


@njit(cache=True)
def impacts_on_floor(f, building, units, st, events, diag):
    """Resolve the simultaneous impacts on floor f (units with events.hit[j]); returns how many.

    The contacts are the units hitting a wall of f and the units resting on
    one; consecutive identical contacts form one group (see solve_impulses).
    """
    ufloor, um, ud, ue = units.floor, units.mass, units.gap, units.restitution
    mode, side, q, v = st.mode, st.side, st.q, st.v
    hit, ev_side, impulse_out, group = events.hit, events.side, events.impulse, events.group
    u, minv, sd, e, count, imp = events.contacts  # per group, the first n entries of each
    nf = building.mass.shape[0]
    nu = um.shape[0]
    n = 0
    for j in range(nu):
        group[j] = -1
        if ufloor[j] != f or not (hit[j] or mode[j] == MODE_STUCK):
            continue
        sj = ev_side[j] if hit[j] else side[j]
        uj = sj * (v[nf + j] - v[f]) if hit[j] else 0.0
        ej = ue[j] if hit[j] else 0.0
        mj = 1.0 / um[j]
        if n > 0 and sd[n - 1] == sj and u[n - 1] == uj and e[n - 1] == ej and minv[n - 1] == mj:
            count[n - 1] += 1.0
        else:
            sd[n] = sj
            u[n] = uj
            e[n] = ej
            minv[n] = mj
            count[n] = 1.0
            n += 1
        group[j] = n - 1
    if n == 0:
        return 0
    mf = floor_mass(f, building, units, mode)
    solve_impulses(u[:n], minv[:n], sd[:n], e[:n], count[:n], mf, imp[:n])
    dv = 0.0
    for a in range(n):
        dv += sd[a] * count[a] * imp[a]
    v[f] += dv / mf
    # the loss is the impulses' work, sum P_k (u_k- + u_k+) / 2: the kinetic energies before and after
    # differ by it, but their difference is round-off of the floor's energy at every impact
    loss = 0.0
    hits = 0
    for j in range(nu):
        g = group[j]
        if g < 0:
            continue
        v[nf + j] -= sd[g] * imp[g] * minv[g]
        if not hit[j] and imp[g] > 0.0:
            # a resting unit that its wall keeps: it moves with its floor, exactly rather than to round-off
            v[nf + j] = v[f]
        loss += 0.5 * imp[g] * (u[g] + sd[g] * (v[nf + j] - v[f]))
        impulse_out[j] = imp[g]
        if hit[j]:
            q[nf + j] = q[f] + sd[g] * 0.5 * ud[j]
            hits += 1
    for j in range(nu):
        if ufloor[j] == f and mode[j] == MODE_LOCKED:
            v[nf + j] = v[f]
    diag[D_IMPLOSS] += loss
    return hits


@njit(cache=True)
def plastic_merge(j, building, units, mode, v, diag):
    """End a rebound too slow to resolve: the unit and its floor take a common velocity."""
    ufloor, um = units.floor, units.mass
    nf = building.mass.shape[0]
    f = ufloor[j]
    mf = floor_mass(f, building, units, mode)
    for l in range(um.shape[0]):
        if l != j and ufloor[l] == f and mode[l] == MODE_STUCK:
            mf += um[l]
    vc, lost = plastic_end(um[j], v[nf + j], mf, v[f])
    diag[D_IMPLOSS] += lost
    v[f] = vc
    v[nf + j] = vc
    for l in range(um.shape[0]):
        if ufloor[l] == f and (mode[l] == MODE_STUCK or mode[l] == MODE_LOCKED):
            v[nf + l] = vc


@njit(cache=True)
def settle(t, model, springs, fric, harm, record, yld, st, scratch):
    """Decide, at one instant, which units the walls or the floor keep holding.

    st.check[j]: 1 a unit that just rebounded (is its rebound resolvable?), 2 a
    unit that just came to rest on a wall or on the floor (does it stay?).
    Repeats until no unit changes, since every change alters the floors' motion.
    """
    p, building, units, load_vec = model.p, model.building, model.units, model.load_vec
    mode, side, offset, check, v = st.mode, st.side, st.offset, st.check, st.v
    w = scratch.seg_work
    kap, C, P, cs, ps, cq, pq, cache = w.kap, w.C, w.P, w.cs, w.ps, w.cq, w.pq, w.cache
    cursor, diag = scratch.cursor, scratch.diag
    jolted = scratch.events.floors_done  # resolve_events is done with it
    ufloor, um, uload, ud = units.floor, units.mass, units.load, units.gap
    nf = building.mass.shape[0]
    nu = um.shape[0]
    omega = p[P_OMEGA]
    r0 = 0.0
    r1 = 0.0
    theta0 = 0.0
    if record is not None:
        r0, r1, _ = record_value(record, p, t)
    if harm is not None:
        theta0 = omega * t + p[P_PHI]
    for _ in range(2 * nu + 2):
        s = config_slot(building, units, springs, yld, load_vec, omega if harm is not None else 0.0, mode, cache,
                        cursor)
        build_segment(w, s, units, springs, fric, yld, harm is not None, (theta0, r0, r1), omega)
        # every unit is judged on the same segment, so identical units decide alike
        changed = False
        for j in range(nu):
            f = ufloor[j]
            if check[j] == 1 and mode[j] == MODE_FREE:
                check[j] = 0
                floor_size = _difference_row(C, P, nf + j, f, cs, ps)
                push = side[j] * deriv_at0(kap, cs, ps, 2)
                tol = _contact_tol(ud[j], bound(kap, cs, ps, 0, 0.0), floor_size)
                if rebound_too_slow(push, v[nf + j] - v[f], tol):
                    plastic_merge(j, building, units, mode, v, diag)
                    hold(st, j)
                    offset[j] = side[j] * 0.5 * ud[j]
                    check[j] = 2
                    changed = True
                    jolted[:] = False
                    jolted[f] = True
                    _follow_floor_jolts(nf, units, fric, st, jolted)
            elif check[j] == 2 and mode[j] == MODE_STUCK:
                stuck_row(kap, C, P, f, side[j], uload[j] * r0, uload[j] * r1,
                          _unit_level(j, units, springs, fric), cq, pq)
                check[j] = 0
                if stays(kap, cq, pq):
                    diag[D_STICKS] += 1.0
                else:
                    leave_wall(st, j, fric is not None)
                    changed = True
            elif check[j] == 2 and mode[j] == MODE_FLOOR:
                check[j] = 0
                if fric is not None:
                    floor_row(kap, C, P, f, uload[j] * r0, uload[j] * r1, cq, pq)
                    slide = floor_decision(kap, cq, pq, fric[j])
                    if slide != 0:
                        start_slide(st, j, slide)
                        changed = True
        if not changed:
            return


@njit(cache=True)
def _record_impacts(t, units, st, events, v_before, recs, diag):
    """Append a record (layout.R_*) of every unit that hit a wall at t while recs has room (count: diag[D_NREC])."""
    ufloor = units.floor
    mode, q, v = st.mode, st.q, st.v
    hit, ev_side, impulse = events.hit, events.side, events.impulse
    nf = v.shape[0] - ufloor.shape[0]
    irec = int(diag[D_NREC])
    for j in range(hit.shape[0]):
        if hit[j] and irec < recs.shape[0]:
            f = ufloor[j]
            record_impact(recs[irec], t, j, ev_side[j], q[f], (v_before[f], v_before[nf + j]), (v[f], v[nf + j]),
                          mode[j] == MODE_STUCK, impulse[j])
            irec += 1
    diag[D_NREC] = irec


@njit(cache=True)
def _gap_roundoff(seg, row, f, tau):
    """The round-off of a unit's gap (its row less its floor's f) at tau into the segment seg was built for (its ek
    is exp(kap tau) there), as sample_segment counts a position's: the event search found the wall on these rows."""
    return row_roundoff(seg.ek, seg.C, seg.P, row, tau) + row_roundoff(seg.ek, seg.C, seg.P, f, tau)


@njit(cache=True)
def resolve_events(tau_ev, building, units, fric, st, events, vstick, seg, diag):
    """Apply every unit's event that falls at this instant (tau_ev into the segment, seg's: bundles.SegmentWork);
    returns the number of impacts."""
    ufloor, um, ud = units.floor, units.mass, units.gap
    mode, side, offset, check, q, v = st.mode, st.side, st.offset, st.check, st.q, st.v
    ev_t, ev_side, ev_kind, hit = events.t, events.side, events.kind, events.hit
    impulse, touched, floors_done = events.impulse, events.touched, events.floors_done
    nf = building.mass.shape[0]
    nu = um.shape[0]
    limit = at_instant(tau_ev)
    for j in range(nu):
        hit[j] = False
        touched[j] = False
        impulse[j] = 0.0
    for i in range(nf):
        floors_done[i] = False
    for j in range(nu):
        if not ev_t[j] <= limit:
            continue
        f = ufloor[j]
        half = 0.5 * ud[j]
        kind = ev_kind[j]
        if kind == EV_RELEASE:
            q[nf + j] = q[f] + side[j] * half
            v[nf + j] = v[f]
            leave_wall(st, j, fric is not None)
        elif kind == EV_FLOOR_EXIT:
            v[nf + j] = v[f]
            start_slide(st, j, -ev_side[j])
        elif kind == EV_SLIDE_STOP:
            v[nf + j] = v[f]
            rest_on_floor(st, j)
            offset[j] = q[nf + j] - q[f]
            check[j] = 2
        elif kind == EV_WALL:
            sd = ev_side[j]
            pen = abs(q[nf + j] - q[f]) - half
            if pen > diag[D_PEN_EXCESS]:  # else it raises neither record (D_PEN >= D_PEN_EXCESS): no round-off count
                note_penetration(diag, pen, _gap_roundoff(seg, nf + j, f, tau_ev))
            if sd * (v[nf + j] - v[f]) <= 0.0:
                # touched within contact tolerance while already separating: at a speed below the sticking
                # one it is resting there (merged below, and the walls decide); else settle judges it as a
                # rebound, which rests on the wall if it cannot clear the tolerance.  Either way the same
                # touch is not found again
                q[nf + j] = q[f] + sd * half
                side[j] = sd
                if abs(v[nf + j] - v[f]) < vstick:
                    touched[j] = True
                else:
                    rebound(st, j)
                    check[j] = 1
            else:
                hit[j] = True
    n_hit = 0
    for j in range(nu):
        if hit[j] and not floors_done[ufloor[j]]:
            floors_done[ufloor[j]] = True
            n_hit += impacts_on_floor(ufloor[j], building, units, st, events, diag)
    for j in range(nu):
        if mode[j] == MODE_STUCK and floors_done[ufloor[j]] and side[j] * (v[nf + j] - v[ufloor[j]]) < 0.0:
            # its wall moved away under another unit's impact; a separation too slow to resolve
            # is judged in settle like any slow rebound.  Released before any merge below, which
            # moves the units still resting on the floor with it
            rebound(st, j)
            check[j] = 1
            meet_wall(st, j, side[j], fric is not None)
    _land_on_walls(building, units, fric, st, events, vstick, diag)
    _follow_floor_jolts(nf, units, fric, st, events.floors_done)
    return n_hit


@njit(cache=True)
def _land_on_walls(building, units, fric, st, events, vstick, diag):
    """Every unit struck or touched at this instant rests on its wall (a rebound too slow to resolve merges it
    with its floor, which jolts the floor: floors_done) or leaves it."""
    ufloor, ud = units.floor, units.gap
    mode, side, offset, check, v = st.mode, st.side, st.offset, st.check, st.v
    ev_side, hit, touched, floors_done = events.side, events.hit, events.touched, events.floors_done
    nf = building.mass.shape[0]
    for j in range(ufloor.shape[0]):
        if not (hit[j] or touched[j]):
            continue
        f = ufloor[j]
        meet_wall(st, j, ev_side[j], fric is not None)
        if abs(v[nf + j] - v[f]) < vstick:
            plastic_merge(j, building, units, mode, v, diag)
            floors_done[f] = True
            hold(st, j)
            offset[j] = side[j] * 0.5 * ud[j]
            check[j] = 2
        else:
            rebound(st, j)
            check[j] = 1


@njit(cache=True)
def _follow_floor_jolts(nf, units, fric, st, jolted):
    """The free and friction-held units on every floor whose velocity jumped at this instant (jolted: an impact or
    a merge, every one of them applied first, so that a slide's direction is read from the floor's final
    velocity): a unit friction held slips, a unit leaving a wall and driven back into it stops leaving, a sliding
    unit's friction turns.  A unit leaving its wall after its own rebound keeps leaving, and friction opposes
    that rebound already."""
    ufloor = units.floor
    mode, escape, v = st.mode, st.escape, st.v
    for j in range(ufloor.shape[0]):
        f = ufloor[j]
        if not jolted[f]:
            continue
        if mode[j] == MODE_FLOOR and v[nf + j] != v[f]:
            # friction cannot pass on an impulse: the floor slips under the unit
            slip(st, j, v[nf + j] - v[f])
        elif mode[j] == MODE_FREE and escape[j] * (v[nf + j] - v[f]) > CONTACT_TOL * (abs(v[nf + j]) + abs(v[f])):
            # leaving a wall, and the floor's jolt drives it back into that wall: no longer leaving, so the
            # search finds the strike at once rather than after it has passed through the wall.  A drive within
            # the contact tolerance of the speeds is round-off (another unit's strike at a speed of one ulp jolts
            # the floor by one ulp): turned back by it, two groups just released on one floor handed such a
            # strike to each other without end (probe scene 3297466453-2244)
            escape[j] = 0
            if fric is not None and fric[j] > 0.0:
                slide_with(st, j, v[nf + j] - v[f])
        elif mode[j] == MODE_FREE and fric is not None and v[nf + j] != v[f]:
            # a sliding unit's floor jumped under another unit's impact: friction now opposes the new slip
            slide_with(st, j, v[nf + j] - v[f])


@njit(cache=True)
def _workspace(nt, nfull, nu, nrows, nmax, slots, nmon):
    """Every array a run works in, allocated once; nrows: the constraint table's rows (bundles.Events)."""
    seg = Segment(np.zeros(nt, dtype=np.complex128), np.zeros((nfull, nt), dtype=np.complex128),
                  np.zeros((nfull, NPOLY)), np.zeros(nt, dtype=np.complex128), np.zeros((nt, nt), dtype=np.complex128),
                  np.zeros((nt, SINGLE_COLUMNS), dtype=np.complex128), np.zeros((nt, nt), dtype=np.complex128),
                  np.zeros((5, nt)))
    rows = Rows(np.zeros(nt, dtype=np.complex128), np.zeros(NPOLY), np.zeros(nt, dtype=np.complex128), np.zeros(NPOLY),
                np.zeros(nt, dtype=np.complex128), np.zeros(NPOLY), np.zeros((nfull, nt), dtype=np.complex128),
                np.zeros((nfull, NPOLY)), np.zeros((2, nt), dtype=np.complex128), np.zeros((2, NPOLY)))
    vecs = Vectors(np.zeros((256, 4)), np.zeros(4), np.zeros(nfull), np.zeros(nfull), np.zeros(nfull), np.zeros(nmax),
                   np.zeros(2 * nmax), np.zeros(nu), np.ones(nt))
    events = Events(np.zeros(nrows), np.zeros(nrows, dtype=np.int64), np.zeros(nrows, dtype=np.int64),
                    np.zeros(nu, dtype=np.bool_), np.zeros(nu), np.zeros(nu, dtype=np.bool_),
                    np.zeros(nfull, dtype=np.bool_), np.zeros(nu, dtype=np.int64), np.zeros((6, nu)))
    step = StepTables(np.full(slots, -1, dtype=np.int64), np.zeros((slots, nt), dtype=np.complex128),
                      np.zeros((slots, nt, nt), dtype=np.complex128),
                      np.zeros((slots, nt, SINGLE_COLUMNS), dtype=np.complex128),
                      np.zeros((slots, nt, nt), dtype=np.complex128))
    scratch = (np.zeros(7 * nmax), np.zeros(4 * nmax, dtype=np.complex128))
    tables = Tables(modal_tables(slots, nmax, nmon, nrows - nu), step, scratch, np.zeros(1, dtype=np.int64))
    return Workspace(seg, rows, vecs, events, tables)


@njit(cache=True)
def _initial_units(units, fric, st):
    """Contact state of every unit at the start: walls to check, friction's floor contact and slide sign."""
    mode, offset, check, q, v = st.mode, st.offset, st.check, st.q, st.v
    ufloor, ud = units.floor, units.gap
    nf = q.shape[0] - ufloor.shape[0]
    for j in range(mode.shape[0]):
        s_j = q[nf + j] - q[ufloor[j]]
        offset[j] = s_j
        if mode[j] != MODE_FREE:
            check[j] = 2
        if fric is not None:
            if mode[j] == MODE_FREE and fric[j] > 0.0:
                rel = v[nf + j] - v[ufloor[j]]
                if rel == 0.0 and abs(s_j) < 0.5 * ud[j]:
                    mode[j] = MODE_FLOOR
                    check[j] = 2
                else:
                    slide_with(st, j, rel)


@njit(cache=True)
def segment_load(p, record, harm, t, t_end):
    """(r0, r1, theta0, t_next, tau_max): the load on the segment from t and where it may end at the latest."""
    r0 = 0.0
    r1 = 0.0
    theta0 = 0.0
    t_next = t_end
    if record is not None:
        r0, r1, t_next = record_value(record, p, t)
        t_next = min(t_next, t_end)
    if harm is not None:
        theta0 = p[P_OMEGA] * t + p[P_PHI]
    tau_max = t_next - t
    if record is not None:
        tau_max = whole_step(p, t, t_next, t_end)
    return r0, r1, theta0, t_next, tau_max


@njit(cache=True)
def integrate_energy(w, s, tau, building, units, springs, harm, record, load_at, yielding):
    """The energy terms over the segment: from the modal tables under a record, from the rows under a harmonic;
    yielding: the building's storeys can yield (its load's work is taken from the state, integrate_modal)."""
    if harm is None:
        integrate_modal(w, s, w.size[s], tau, units, record, load_at[1], load_at[2], yielding)
    else:
        integrate_segment(w, tau, building, units, springs, harm, record, load_at)


@njit(cache=True)
def move_to_end(w, building, units, springs, fric, yld, tau, s, wave, from_itself):
    """The state at the segment's end, the friction and plastic work on the way, and the largest stored energy.

    from_itself: the state is advanced mode by mode from itself (segment.flow_change), not read off the rows, whose
    parts beside a stiffness near zero are far larger than the motion: while a storey yields (its post-yield
    stiffness), and on every segment of a scene past the model's stability bound (layout.P_FROM_ITSELF).  With
    every storey elastic within the bound it is read off the rows, as an elastic building's always was
    (docs/model.md, "Near zero the flow loses digits").  s: the segment's configuration slot; wave: (harmonic,
    theta0, omega), whether the load is harmonic, its phase at the segment's start and its frequency."""
    harmonic, theta0, omega = wave
    mode, sigma, kap, ek, C, P, q, v = w.mode, w.sigma, w.kap, w.ek, w.C, w.P, w.q, w.v
    s_before, diag = w.s_before, w.diag
    nf = building.mass.shape[0]
    ufloor = units.floor
    if fric is not None:
        for j in range(mode.shape[0]):
            s_before[j] = q[nf + j] - q[ufloor[j]]
    if from_itself:
        flow_change(w, s, tau, harmonic, theta0)
        take_flow_state(w, s, tau, harmonic, theta0, omega, units, nf)
    else:
        state_from_exp(kap, ek, C, P, tau, q, v)
    if fric is not None:
        for j in range(mode.shape[0]):
            if mode[j] == MODE_FREE and fric[j] > 0.0:
                # s' keeps its sign on a sliding segment: the work is exact
                slid = q[nf + j] - q[ufloor[j]] - s_before[j]
                diag[D_FRICTION] += units.mass[j] * fric[j] * sigma[j] * slid
    if yld is not None:
        plastic_flow(yld, q, diag)
    e_now = energy(building, units, springs, yld, nf, q, v)
    if yld is not None:
        # the balance's scale: P-delta's -P u^2 / (2h) is counted by its size, since a building falling over turns
        # gravity's energy into motion while its total stays small
        e_now += storey_gravity(yld, q)
    if e_now > diag[D_EMAX]:
        diag[D_EMAX] = e_now


@njit(cache=True)
def handle_events(t, tau, model, springs, fric, harm, record, yld, st, scratch):
    """Apply the events found at t (the units' and the storeys'), settle the contacts they leave and record the
    impacts."""
    p, diag = model.p, scratch.diag
    v, v_before = st.v, scratch.v_before
    for i in range(v.shape[0]):
        v_before[i] = v[i]
    n_hit = resolve_events(tau, model.building, model.units, fric, st, scratch.events, p[P_VSTICK], scratch.seg_work,
                           diag)
    if yld is not None:
        resolve_storeys(tau, yld, scratch.events, model.units.mass.shape[0], st.q, st.v, diag)
        storey_jumps(yld, st.q, st.v, diag, n_hit > 0)  # an impact, or a resting unit's merge, moved a floor
    if n_hit > 0:
        diag[D_IMPACTS] += n_hit
        if t >= p[P_TWIN]:
            diag[D_IMPACTS_WIN] += n_hit
        if n_hit > 1:
            diag[D_SIMULTANEOUS] += 1.0
    settle(t, model, springs, fric, harm, record, yld, st, scratch)
    if yld is not None:
        storey_jumps(yld, st.q, st.v, diag, False)  # settle's plastic merges move floors too
    if n_hit > 0:
        _record_impacts(t, model.units, st, scratch.events, v_before, scratch.recs, diag)


@njit(cache=True)
def _start(t, model, springs, fric, harm, record, yld, st, scratch, out):
    """The state a run starts from: contacts decided by the walls, diagnostics and monitors zeroed."""
    diag = out.diag
    for i in range(NDIAG):
        diag[i] = 0.0
    _initial_units(model.units, fric, st)
    settle(t, model, springs, fric, harm, record, yld, st, scratch)
    nf = model.building.mass.shape[0]
    diag[D_STICKS] = 0.0  # a unit placed on a wall is not a sticking episode
    diag[D_E0] = energy(model.building, model.units, springs, yld, nf, st.q, st.v)
    diag[D_EMAX] = diag[D_E0]
    for m in range(out.peak.shape[0]):
        out.peak[m] = 0.0
        out.peak_t[m] = t
        out.x2[m] = 0.0
        out.roundoff[m] = 0.0


@njit(cache=True)
def _instant_scratch(w, ws, out):
    """What the steps at an event's instant work in (bundles.InstantScratch), from the borrowed workspace and
    outputs."""
    return InstantScratch(w, ws.tables.cursor, ws.events, ws.vecs.v_before, out.recs, out.diag)


@njit(cache=True)
def _clear_scratch(clear, nfull, nmon, yld):
    """What clear_steps works in (its `scratch`), allocated once per run; empty arrays without a clear step."""
    if clear is None:
        return (np.empty(0), np.empty(0), np.empty(0), np.empty(0), np.empty(0), np.empty(0), np.empty(0))
    n2 = 2 * nfull
    nband = clear.half.shape[0] + (yld.branch.shape[0] if yld is not None else 0)
    return (np.empty(clear.flow.shape[1]), np.empty(n2), np.empty(n2),
            np.empty(n2 + clear.inv.shape[0] // clear.masks.shape[0]), np.empty(2 * nmon), np.empty(nband),
            np.empty(nband))


@njit(cache=True)
def _segment_work(ws, st, out, cache, load_vec, owner):
    """The SegmentWork of a run, from its borrowed workspace, state, outputs, cache and load vector (reading a
    borrowed array counts no reference).  `owner` holds what the views are of and the caller does not (the
    workspace, the state and the clear step's scratch); the outputs, the cache and the load vector are
    run_scene's arguments, which its caller holds."""
    seg, rows, vecs, ev, mtab, work = ws.seg, ws.rows, ws.vecs, ws.events, ws.tables.modal, ws.tables.work
    return SegmentWork(seg.kap, seg.C, seg.P, seg.ek, seg.pair, seg.single, seg.ramp, seg.kpow,
                       rows.cs, rows.ps, rows.cq, rows.pq, rows.cm, rows.pm, rows.cv, rows.pv, rows.cu, rows.pu,
                       vecs.stack, vecs.found, vecs.reduced, vecs.moduli, vecs.s_before, vecs.wt,
                       ev.t, ev.side, ev.kind, cache, load_vec, st.mode, st.side, st.sigma, st.offset,
                       st.escape, st.escape_v, st.q, st.v, out.diag, out.peak, out.peak_t, out.x2, out.roundoff,
                       cache.size, cache.lam, cache.vec, cache.vinv, cache.kinv, cache.damping, cache.dof,
                       cache.load, cache.forced, cache.mass, mtab.gvis, mtab.lmod, mtab.mvec, mtab.mbnd, mtab.reach,
                       work[0], work[1], owner)


@njit(cache=True)
def run_scene(model, springs, fric, harm, record, yld, clear, start, cache, out):
    """One run from p[P_T0] to p[P_TEND], its results written into out (bundles.RunOutputs); returns the number
    of impact records written.

    model: bundles.SceneArrays; start: bundles.StartState, with every unit's initial contact state (the
    walls decide at once whether they hold a unit placed against them); cache: a bundles.ConfigCache
    that the run fills; yld: a yielding building's bundles.YieldArrays (None for an elastic one), whose state
    the run advances from where it is and leaves as its result; clear: a bundles.ClearStep for a scene whose whole
    record steps may be taken by matrices (clear_step; None: every step by the segment's rows).
    """
    model = borrowed(model)
    p, building, units, load_vec, monitors = model
    nf = building.mass.shape[0]
    nu = units.mass.shape[0]
    nt = cache.lam.shape[1] + (2 if harm is not None else 0)
    nrows = nu + (yld.branch.shape[0] if yld is not None else 0)
    ws = _workspace(nt, nf + nu, nu, nrows, cache.kinv.shape[1], cache.key.shape[0], monitors.rows.shape[0])
    st = RunState(start.mode.copy(), start.side.copy(), np.zeros(nu, dtype=np.int64), np.zeros(nu),
                  np.zeros(nu, dtype=np.int64), np.zeros(nu, dtype=np.int64), np.zeros(nu, dtype=np.int64),
                  start.q.copy(), start.v.copy())
    clear_owned = _clear_scratch(clear, nf + nu, monitors.kind.shape[0], yld)
    # the loop binds every array it hands a step borrowed (bundles.borrowed): bound as they are, each costs an
    # atomic reference count at every step they are handed to.  The SegmentWork holds what run_scene owns
    # (the workspace, the state, the clear step's scratch); the caller holds the arguments
    ws_b, st_b, out_b, cache = borrowed(ws), borrowed(st), borrowed(out), borrowed(cache)
    # the steps on every segment take one structref of the arrays they work in (impact.engine.bundles)
    w = _segment_work(ws_b, st_b, out_b, cache, load_vec, (ws, st, clear_owned))
    kap, C, P, ek, pair, single, ramp, kpow = ws_b.seg
    qs, vs, aw, wt = ws_b.vecs.qs, ws_b.vecs.vs, w.aw, w.wt
    mtab, dtab, cursor = ws_b.tables.modal, ws_b.tables.step, ws_b.tables.cursor
    wc = w.wc  # the segment's modal amplitudes are wc[2n:4n] (build_segment)
    mode, escape, escape_v = st_b.mode, st_b.escape, st_b.escape_v
    q, v = st_b.q, st_b.v
    diag, ts, samples = out_b.diag, out_b.ts, out_b.samples
    peaks = (out_b.peak, out_b.peak_t, monitors.cap, monitors.share, out_b.x2)
    # the optional parts, borrowed to the compiled steps (None stays None); each step prunes its branches on
    # `is None` on its own argument
    springs_b, fric_b, harm_b, record_b, yld_b = borrowed(springs), borrowed(fric), borrowed(harm), \
        borrowed(record), borrowed(yld)
    # the compiled steps at an event's instant take the state and their scratch borrowed too
    instant = _instant_scratch(w, ws_b, out_b)
    t = p[P_T0]
    t_end = p[P_TEND]
    t_square = p[P_TWIN] if p[P_WINDOW] != 0.0 else np.inf  # where the roof's square starts: never if unread
    _start(t, model, springs_b, fric_b, harm_b, record_b, yld_b, st_b, instant, out)
    its = 0  # the next sample time
    while its < ts.shape[0] and ts[its] < t:
        its += 1
    clock = np.array([math.floor(t / p[P_PERIOD]), 0.0, t, 0.0, 0.0])
    # what the slot, |kap|^n and the integral tables were last found for: scalars, not an array, so that
    # they stay in registers (an inlined helper returning them cost 15 % of a run)
    slot_key = -1
    kpow_key = -1
    tab_key = -1
    tab_tau = -1.0
    s = 0
    rate = 0.0  # the configuration's growth rate (growth_rate), 0 unless a storey's P-delta outweighs it
    always_from_itself = yld is not None and p[P_FROM_ITSELF] != 0.0  # else only while a storey yields
    omega = p[P_OMEGA]
    if clear is not None:
        clear_b, clear_scratch = borrowed(clear), borrowed(clear_owned)
    while t < t_end:
        if clear is not None and _all_free(mode, escape) and _storeys_settled(yld_b):
            t = clear_steps(clear_b, clear_scratch, (q, v, diag), peaks, (p, record_b),
                            (t, t_end, t_square, ts[its] if its < ts.shape[0] else np.inf), building, units,
                            springs_b, yld_b)
        r0, r1, theta0, t_next, tau_max = segment_load(p, record_b, harm_b, t, t_end)
        key = scene_key(mode, yld_b)
        if key != slot_key:
            s = config_slot(building, units, springs_b, yld_b, load_vec, omega if harm is not None else 0.0, mode, cache,
                            cursor)
            if yld is not None:
                rate = growth_rate(cache, s)
            modal_slot(s, key, cache, nf, units, mode, monitors.rows, monitors.kind, mtab,
                       math.e if rate > 0.0 else 1.0)
            slot_key = key
        if rate > 0.0 and tau_max * rate > 1.0:
            tau_max = 1.0 / rate
            t_next = t + tau_max
        build_segment(w, s, units, springs_b, fric_b, yld_b, harm is not None, (theta0, r0, r1), omega)
        if key != kpow_key:
            kappa_powers(kap, kpow)
            if rate > 0.0:
                grow_powers(kap, kpow)
            mode_weights(kap, wt)
            kpow_key = key
        if record is not None and (key != tab_key or tau_max != tab_tau):
            # sampled loads repeat the same step in the same configuration: the tables carry over
            step_tables(s, key, tau_max, p[P_REC_DT], kap, ek, pair, single, ramp, dtab)
            tab_key = key
            tab_tau = tau_max
        diag[D_SEGMENTS] += 1.0
        n = cache.size[s]
        amplitude_moduli(n, wc, aw)
        best = search_constraints(w, s, units, springs_b, fric_b, yld_b, tau_max, (r0, r1),
                                  tab_tau if key == tab_key else -1.0, harm is not None)
        event = best <= tau_max and best < np.inf
        tau = best if event else tau_max
        if key != tab_key or tau != tab_tau:
            step_tables(s, key, tau, p[P_REC_DT] if record is not None else -1.0, kap, ek, pair, single, ramp, dtab)
            tab_key = key
            tab_tau = tau
        if harm is None and (record is None or tau != p[P_REC_DT]):
            # the ramp form's tables of any other step than a whole sample step (step_tables keeps those), made
            # once the step is known; a harmonic load's rows have no ramp and integrate term by term
            ramp_tables(kap, ek, tau, ramp, single)
        on_branch = key >> nu != 0  # a storey yielding
        from_itself = on_branch or always_from_itself
        if from_itself and (record is None or tau != p[P_REC_DT]):
            flow_tables(kap, ek, tau, single)  # a whole sample step's come with step_tables
        if not on_branch:
            integrate_energy(w, s, tau, building, units, springs_b, harm_b, record_b, (theta0, r0, r1), yld is not None)
        else:
            # a storey yielding: the rows integrate.  A zero mode's particular velocity is not constant, which the
            # modal tables assume; and beside a stiff pendulum the tables lost 3e-9 of a probe scene's energy
            # balance on the yielding branches, the rows 2.6e-10 (tests/test_exactness.py, yielding probe 97)
            integrate_segment(w, tau, building, units, springs_b, harm_b, record_b, (theta0, r0, r1))
        monitor_modal(w, s, n, tau, t, t_square, monitors, (r0, r1), harm is not None, yld is not None)
        if its < ts.shape[0]:
            its = sample_segment(kap, C, P, t, tau, ts, its, samples, qs, vs)
        move_to_end(w, building, units, springs_b, fric_b, yld_b, tau, s, (harm is not None, theta0, omega), from_itself)
        t = t_next if not event else t + tau
        for j in range(nu):
            if escape[j] != 0 and not _still_leaving(j, nf, units, mode, escape, q, v):
                escape[j] = 0
            escape_v[j] = 0
        if yld is not None:
            storeys_after_segment(yld_b, q, v)
        if not event:
            continue
        stop = event_cap_reached(t, p, clock)
        if stop != 0:
            diag[D_CAP] = stop
            name_stop(tau, ws.events, nu, diag)
            break
        handle_events(t, tau, model, springs_b, fric_b, harm_b, record_b, yld_b, st_b, instant)
        if diag[D_COLLAPSE] != 0.0:
            break
        slot_key = -1  # settle may have filled (and so replaced) cache slots
        tab_key = -1
        kpow_key = -1
    diag[D_E1] = energy(building, units, springs_b, yld_b, nf, q, v)
    diag[D_TEND] = t
    for i in range(nf + nu):
        out.q[i] = q[i]
        out.v[i] = v[i]
    for j in range(nu):
        out.contact[j, 0] = mode[j]
        out.contact[j, 1] = st.side[j]
        out.contact[j, 2] = st.sigma[j]
    return int(diag[D_NREC])

