"""Certified searches on one coefficient-form row: the first exit from a band, and the peak.

On [a, b] a function with |h''| <= M2 stays within max(h(a), h(b)) + M2 (b-a)^2 / 8.
The contact search accepts a step only when a bound of this kind keeps h inside
its band, so a contact cannot be missed however briefly it lasts; a crossing is
refined by safeguarded Newton once monotonicity is certified.  Three bounds
certify a step, whichever holds: that one; h' of one sign (with |h'''| <= M3, h'
stays within its end values widened by M3 (b-a)^2 / 8), so that h lies between
its end values; and the cubic Hermite interpolant of h's values and slopes at
both ends, within M4 (b-a)^4 / 384 of h.  The last two let one step span most
of a flight between the walls.  The first bound also prunes the peak search: an
interval whose bound cannot beat the running peak is dropped, and the others are
split or searched for a zero of h'.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact.engine.segment import bound_tab, deriv_at0, eval2, eval3, poly_at, poly_slope_at

HMIN = 1e-12       # smallest step before a touch is declared tangential
_EPS = 2.220446049250313e-16
PEAK_RTOL = 1e-12  # the peak search stops refining an interval within this of the running peak
PEAK_MAX_VISITS = 100000  # a function of pure round-off could split forever: give up, and say so
PEAK_VISITS_PER_EXTREMUM = 64  # ... but not before a long segment of a fast mode had this many visits per extremum
PEAK_NOISE = 64 * _EPS  # the round-off of evaluating a row, relative to the sum of its terms' sizes
TAYLOR_TURNS = 8.0  # the fastest mode's turn over a segment (radians) up to which its series bounds it ...
TAYLOR_ORDERS = 80  # ... in this many terms at most (_taylor_bound)
TAYLOR_PIECES = 16  # ... and over at most this many pieces of a segment, each from its own start
_FINISHED, _GAVE_UP, _STACK_FULL = 0, 1, 2  # how a peak search ended


@njit(cache=True)
def raise_peak(peak, peak_t, share, m, value, at):
    """Monitor m's new running peak, value at time at, written for every monitor sharing it: the members of a group
    of which only the largest peak is certified hold one running peak, so that the group's largest settles a
    member's step where the member's own smaller peak could not (share[m]: the group's first monitor, m where the
    monitor's own peak is certified; a group's members are consecutive)."""
    first = share[m]
    j = first
    while j < peak.shape[0] and share[j] == first:
        peak[j] = value
        peak_t[j] = at
        j += 1


@njit(cache=True)
def _newton_in_bracket(kap, c, p, level, side, a, b, t, of_slope, iterations):
    """Safeguarded Newton on g = side (f - level), f = h (or h' with of_slope), g(a) < 0 <= g(b).

    Returns the last iterate and the bracket end with g >= 0.
    """
    g_before = np.nan
    for _ in range(iterations):
        if of_slope:
            _, f, df = eval3(kap, c, p, t)
        else:
            f, df = eval2(kap, c, p, t)
        g = side * (f - level)
        if g >= 0.0:
            b = t
        else:
            a = t
        if b - a <= 4.0 * _EPS * max(abs(b), 1e-300):
            break
        dg = side * df
        tn = t - g / dg if dg != 0.0 else 0.5 * (a + b)
        if not (a < tn < b):
            tn = 0.5 * (a + b)
        elif g < 0.0 and g == g_before:
            # a plateau short of the crossing: where h is a difference of far larger terms it reads the same
            # over many ulps, Newton creeps across it, and b, the answer, would stay where the bracket began
            tn = 0.5 * (a + b)
        g_before = g
        if tn == t:
            break
        t = tn
    return t, b


@njit(cache=True)
def refine(kap, c, p, level, side, a, b, ha, hb):
    """Time of the crossing of `level` in [a, b], h monotone there, h(a) = ha and h(b) = hb.

    g = side (h - level) has g(a) < 0 <= g(b).  Newton starts where the chord meets the level.
    Returns the bracket end with g >= 0, so the state is at (never before) the crossing.
    """
    t = a + (b - a) * (level - ha) / (hb - ha) if hb != ha else 0.5 * (a + b)
    if not a < t < b:
        t = 0.5 * (a + b)
    return _newton_in_bracket(kap, c, p, level, side, a, b, t, False, 200)[1]


@njit(cache=True)
def _escape_guess(h1, h2, h3, noise, delta):
    """A first look for the clearance from h's derivatives at the edge; a derivative within its round-off
    (noise) says nothing, and with none left the look starts from HMIN and doubles."""
    te = np.inf
    if abs(h1) > noise[0]:
        te = min(te, delta / abs(h1))
    if abs(h2) > noise[1]:
        te = min(te, math.sqrt(2.0 * delta / abs(h2)))
    if abs(h3) > noise[2]:
        te = min(te, (6.0 * delta / abs(h3)) ** (1.0 / 3.0))
    if not te < np.inf:
        te = HMIN
    return max(0.25 * te, HMIN)


@njit(cache=True)
def _leave_boundary(kap, kpow, c, p, lo, hi, tau_max, escape, delta, out):
    """Leave the band edge `escape` starts on; returns the clear time, or -1 with out filled.

    For the first tiny steps h(tau) - h(0) is round-off, so separation is
    proven by the Taylor expansion at 0 with its remainder; once steps are
    long enough, by direct evaluation.  Either way the whole way to the clear
    time is certified not to pass the edge by more than delta (_behind_edge), not
    only its end: a release whose first three derivatives are round-off can move
    inward, come back through the wall and be inside again by the time it is looked at.
    """
    edge = hi if escape > 0 else lo
    # the row meets its state to round-off of its terms, which an ill-conditioned modal basis (a stiff
    # pendulum beside a soft building) makes larger than delta: a start read beyond the edge must be
    # travelled back before the clearance counts, or the first step finds the edge it is leaving
    h0 = deriv_at0(kap, c, p, 0)
    behind = min(escape * (edge - h0), 0.0)
    h1 = deriv_at0(kap, c, p, 1)
    h2 = deriv_at0(kap, c, p, 2)
    h3 = deriv_at0(kap, c, p, 3)
    m2 = bound_tab(kpow, c, p, 2, tau_max)
    m3 = bound_tab(kpow, c, p, 3, tau_max)
    m4 = bound_tab(kpow, c, p, 4, tau_max)
    # before this, h cannot reach the far edge (|h - h(0)| <= |h'(0)| t + M2 t^2 / 2): a clearance seen
    # later could lie beyond it, in a gap the motion crosses faster than the derivatives at 0 suggest
    te_far = _time_to_travel(hi - lo, abs(h1), m2)
    te = min(_escape_guess(h1, h2, h3, _rounding(kpow, c, p), delta), te_far, tau_max)
    # g = escape h must stay below this on the way out: the edge, passed by no more than delta
    limit = escape * edge + delta - behind
    ta = 0.0  # certified up to here, with g and g' there
    ga = escape * h0
    dga = escape * h1
    last_clear = 0.0
    steps = 0.0
    while True:
        steps += 1.0
        pred = escape * (h1 * te + 0.5 * h2 * te * te + h3 * te * te * te / 6.0)
        rise = te * (max(escape * h1, 0.0) + te * (0.5 * max(escape * h2, 0.0)
                                                   + te * (max(escape * h3, 0.0) / 6.0 + te * m4 / 24.0)))
        if behind - (pred + m4 * te ** 4 / 24.0) >= delta and rise < delta:
            break  # clear at te, and no Taylor term can have carried h past the edge before it
        if te > 1e3 * HMIN:
            hb, dhb = eval2(kap, c, p, te)
            clearance = escape * (edge - hb)
            mid = ta + 0.5 * (te - ta)
            can_halve = te - ta > HMIN and ta < mid < te and mid > 1e3 * HMIN
            if clearance <= 0.0 and escape * dhb > 16.0 * _EPS * bound_tab(kpow, c, p, 1, te):
                # back at the edge before separating by delta, and moving out by more than the round-off of
                # h' (which is all a slope is this close to a release whose low derivatives vanish): a grazing
                # contact
                if last_clear > 0.0:
                    hl, _ = eval2(kap, c, p, last_clear)
                    te = refine(kap, c, p, edge, escape, last_clear, te, hl, hb)
                elif escape * hb > limit and can_halve:
                    te = mid  # through the edge by more than delta, with no clear time to refine from: it
                    continue  # came back before te, and a shorter stride finds where
                return _touch(te, escape, steps, out)
            if not _behind_edge(ga, dga, escape * hb, escape * dhb, te - ta, m2, m3, m4, limit):
                if can_halve:
                    te = mid  # too long a stride to certify from the last certified time
                    continue
                return _touch(te, escape, steps, out)  # no shorter stride certifies: the edge is met here
            ta = te
            ga = escape * hb
            dga = escape * dhb
            if clearance >= delta:
                break
            if clearance > 0.0:
                last_clear = te
        if te >= tau_max:
            out[0] = np.inf
            out[1] = 0.0
            out[3] = steps
            return -1.0
        if te >= te_far:
            break  # not yet clear: the search goes on from here, where a touch of the edge is a contact
        te = min(2.0 * te, te_far, tau_max)
    out[3] = steps
    return te


@njit(cache=True)
def _touch(te, escape, steps, out):
    """The escape meets its edge again at te: a grazing contact, for first_exit to report (returns -1)."""
    out[0] = te
    out[1] = escape
    out[2] += 1.0
    out[3] = steps
    return -1.0


@njit(cache=True)
def _behind_edge(ga, dga, gb, dgb, w, m2, m3, m4, limit):
    """g certified below limit on [0, w] from its values and slopes at both ends, by any of the module's
    three bounds (g's second, third and fourth derivatives bounded by m2, m3, m4)."""
    if max(ga, gb) + m2 * w * w / 8.0 < limit:
        return True
    if max(ga, gb) < limit and _one_sign(dga, dgb, m3, w) != 0:
        return True
    return _hermite_inside(ga, dga, gb, dgb, w, m4, -np.inf, limit)


@njit(cache=True)
def _rounding(kpow, c, p):
    """The round-off of h's first three derivatives at 0, from the sizes of their terms (bound_tab at 0)."""
    return (16.0 * _EPS * bound_tab(kpow, c, p, 1, 0.0), 16.0 * _EPS * bound_tab(kpow, c, p, 2, 0.0),
            16.0 * _EPS * bound_tab(kpow, c, p, 3, 0.0))


@njit(cache=True)
def _time_to_travel(width, speed, m2):
    """The least t with speed t + m2 t^2 / 2 = width: nothing slower covers the width sooner."""
    if not width < np.inf:
        return np.inf
    if m2 <= 0.0:
        return width / speed if speed > 0.0 else np.inf
    return 2.0 * width / (speed + math.sqrt(speed * speed + 2.0 * m2 * width))


@njit(cache=True)
def _one_sign(d0, d1, m3, w):
    """+1 / -1 when h' is certified positive / negative on an interval of width w with end slopes d0, d1."""
    spread = m3 * w * w / 8.0
    if min(d0, d1) - spread > 0.0:
        return 1
    if max(d0, d1) + spread < 0.0:
        return -1
    return 0


@njit(cache=True)
def _hermite_inside(h0, d0, h1, d1, w, m4, lo, hi):
    """h certified inside (lo, hi) on [0, w]: the cubic Hermite interpolant's extremes, widened by its error
    bound m4 w^4 / 384 and by the round-off of forming it."""
    slope = (h1 - h0) / w
    c2 = (3.0 * slope - 2.0 * d0 - d1) / w
    c3 = (d0 + d1 - 2.0 * slope) / (w * w)
    top = max(h0, h1)
    bot = min(h0, h1)
    # interior extrema where H' = d0 + 2 c2 s + 3 c3 s^2 vanishes
    qa = 3.0 * c3
    qb = 2.0 * c2
    s1 = -1.0
    s2 = -1.0
    if qa != 0.0:
        disc = qb * qb - 4.0 * qa * d0
        if disc >= 0.0:
            root = math.sqrt(disc)
            s1 = (-qb - root) / (2.0 * qa)
            s2 = (-qb + root) / (2.0 * qa)
    elif qb != 0.0:
        s1 = -d0 / qb
    for s in (s1, s2):
        if 0.0 < s < w:
            v = h0 + s * (d0 + s * (c2 + s * c3))
            top = max(top, v)
            bot = min(bot, v)
    err = m4 * w * w * w * w / 384.0 + 16.0 * _EPS * (abs(h0) + abs(h1) + w * (abs(d0) + abs(d1)))
    return top + err < hi and bot - err > lo


@njit(cache=True)
def _step_guess(margin, dh, h, lo, hi, m2, m3, m4):
    """A first step: the longest of the spans each certificate can be expected to accept, but no farther
    than a little past where the slope would take h to the wall it heads for (there the step finds the
    crossing with h monotone, ready to refine)."""
    step = math.sqrt(4.0 * margin / m2) if m2 > 0.0 else np.inf
    if m3 > 0.0:
        step = max(step, 0.5 * math.sqrt(8.0 * abs(dh) / m3))
    if m4 > 0.0:
        step = max(step, math.sqrt(math.sqrt(192.0 * margin / m4)))
    if dh > 0.0 and hi < np.inf:
        step = min(step, 1.2 * (hi - h) / dh)
    elif dh < 0.0 and lo > -np.inf:
        step = min(step, 1.2 * (h - lo) / -dh)
    return max(step, HMIN)


@njit(cache=True)
def first_exit(kap, kpow, c, p, lo, hi, tau_max, escape, delta, out):
    """First tau in (0, tau_max] where h leaves (lo, hi).

    escape = +1/-1: h starts on hi/lo and is leaving it (after an impact or a
    release); re-contact closer than the contact tolerance `delta` is not
    resolved.  kpow: |kap|^n, n = 0..4 (segment.kappa_powers).  Writes out[0] = tau (inf if none),
    out[1] = side (+1 hi, -1 lo, 0 none), out[2] = grazing passes, out[3] = steps taken.
    """
    out[2] = 0.0
    out[3] = 0.0
    a = 0.0
    if escape != 0:
        a = _leave_boundary(kap, kpow, c, p, lo, hi, tau_max, escape, delta, out)
        if a < 0.0:
            return
    m2 = bound_tab(kpow, c, p, 2, tau_max)
    m3 = bound_tab(kpow, c, p, 3, tau_max)
    m4 = bound_tab(kpow, c, p, 4, tau_max)
    steps = out[3]
    grazing = 0.0
    ha, dha = eval2(kap, c, p, a)
    near = False
    while a < tau_max:
        margin = max(min(hi - ha, ha - lo), 0.0)
        hstep = _step_guess(margin, dha, ha, lo, hi, m2, m3, m4)
        while True:
            b = min(a + hstep, tau_max)
            w = b - a
            hb, dhb = eval2(kap, c, p, b)
            steps += 1.0
            sign = _one_sign(dha, dhb, m3, w)
            if hb >= hi or hb <= lo:
                side = 1.0 if hb >= hi else -1.0
                monotone = side * dha - m2 * w > 0.0 or side * dhb - m2 * w > 0.0 or sign == side
                if monotone or w <= HMIN:
                    level = hi if side > 0 else lo
                    out[0] = refine(kap, c, p, level, side, a, b, ha, hb)
                    out[1] = side
                    out[2] = grazing + (0.0 if monotone else 1.0)
                    out[3] = steps
                    return
                hstep = 0.5 * w
                continue
            spread = m2 * w * w / 8.0
            if max(ha, hb) + spread < hi and min(ha, hb) - spread > lo:
                break
            if sign != 0 and lo <= ha <= hi:
                break  # h monotone between two values inside the band
            if _hermite_inside(ha, dha, hb, dhb, w, m4, lo, hi):
                break
            if w <= HMIN:
                break  # a tangency within round-off of the edge
            hstep = 0.5 * w
        close = min(hi - hb, hb - lo) < delta
        if close and not near:
            grazing += 1.0
        near = close
        a = b
        ha = hb
        dha = dhb
    out[0] = np.inf
    out[1] = 0.0
    out[2] = grazing
    out[3] = steps


@njit(cache=True)
def _zero_of_derivative(kap, c, p, a, b, da):
    """A zero of h' in (a, b) where h' changes sign (h'(a) = da): safeguarded Newton on h'."""
    side = -1.0 if da > 0.0 else 1.0  # g = side h' < 0 at a
    return _newton_in_bracket(kap, c, p, 0.0, side, a, b, 0.5 * (a + b), True, 100)[0]


@njit(cache=True)
def _ends(kap, ek, c, p, big_t):
    """h(0), h'(0), h(T), h'(T) from ek = exp(kap T): no exponentials to evaluate."""
    h0 = p[0]
    d0 = p[1]
    h1 = poly_at(p, big_t)
    d1 = poly_slope_at(p, big_t)
    for k in range(kap.shape[0]):
        ck = c[k]
        if ck.real != 0.0 or ck.imag != 0.0:
            ckk = ck * kap[k]
            h0 += ck.real
            d0 += ckk.real
            h1 += (ck * ek[k]).real
            d1 += (ckk * ek[k]).real
    return h0, d0, h1, d1


@njit(cache=True)
def _probe(kap, c, p, t, peak, at):
    """h at t, kept as the running peak if larger: returns (peak, where, h'(t))."""
    h, dh = eval2(kap, c, p, t)
    if abs(h) > peak:
        return abs(h), t, dh
    return peak, at, dh


@njit(cache=True)
def _push(stack, top, a, b, da, db):
    """An interval [a, b] with its end slopes onto the search's stack; returns the new top."""
    stack[top, 0] = a
    stack[top, 1] = b
    stack[top, 2] = da
    stack[top, 3] = db
    return top + 1


@njit(cache=True)
def _extrema_bound(kap, big_t):
    """How many extrema the fastest mode can have over [0, T] (one per half period): the peak search may
    visit each a few times before a function of pure round-off is the better explanation."""
    fastest = 0.0
    for k in range(kap.shape[0]):
        fastest = max(fastest, abs(kap[k].imag))
    return 1.0 + fastest * big_t / math.pi


@njit(cache=True)
def _unsearched_bound(kap, c, p, stack, top, m2):
    """The largest |h| the intervals still on the stack can hold (their ends and the curvature bound)."""
    bound = 0.0
    for i in range(top):
        a = stack[i, 0]
        b = stack[i, 1]
        ha, _ = eval2(kap, c, p, a)
        hb, _ = eval2(kap, c, p, b)
        bound = max(bound, max(abs(ha), abs(hb)) + m2 * (b - a) * (b - a) / 8.0)
    return bound


@njit(cache=True)
def shift_row(kap, c, p, a, cs, ps):
    """The row h(a + tau) as a row in tau (cs, ps: its terms and polynomial)."""
    for k in range(kap.shape[0]):
        cs[k] = c[k] * np.exp(kap[k] * a)
    ps[0] = poly_at(p, a)
    ps[1] = poly_slope_at(p, a)
    ps[2] = p[2] + 3.0 * a * p[3]
    ps[3] = p[3]


@njit(cache=True)
def _split_taylor_bound(kap, c, p, big_t):
    """The smallest bound of |h| over [0, T] by Taylor series (_taylor_bound) at the starts of 1, 2, 4, ...
    TAYLOR_PIECES equal pieces, the largest over a split's pieces.  Decaying modes turning about a radian each make
    the series' higher orders alternate, which its bound takes at their sizes; a piece of width T / m shrinks order
    n by m^n.  A drift of 1e-19 m written with terms of 1e-5 m (probe scene 3428279703-1757) was bounded at 5e-17 m
    over the whole segment.  A piece's terms are seen from its start (c_k e^{kap_k a}, the polynomial shifted), whose
    round-off, PEAK_NOISE of the row's size over the segment, is added to each split's bound."""
    best = _taylor_bound(kap, c, p, big_t)
    size = 0.0
    for k in range(kap.shape[0]):
        size += abs(c[k]) * max(1.0, math.exp(kap[k].real * big_t))
    for n in range(4):
        size += abs(p[n]) * big_t ** n
    cs = np.empty_like(c)
    ps = np.empty(4)
    pieces = 2
    while pieces <= TAYLOR_PIECES:
        width = big_t / pieces
        worst = 0.0
        for i in range(pieces):
            shift_row(kap, c, p, i * width, cs, ps)
            worst = max(worst, _taylor_bound(kap, cs, ps, width))
        best = min(best, worst + PEAK_NOISE * size)
        pieces *= 2
    return best


@njit(cache=True)
def _taylor_bound(kap, c, p, big_t):
    """A bound of |h| over [0, T] from its Taylor series at 0, over the modes turning by at most TAYLOR_TURNS
    radians over T, and the faster ones bounded each by its size (inf if the series does not settle).

    Each coefficient is summed over the terms and the polynomial before its size is taken, so terms that cancel
    (the absolute acceleration of a floor at rest, written as a relative and a ground part of metres per second
    squared each) bound it by what is left and by the coefficient's round-off, not by their own sizes, as the
    curvature bounds of the branch and bound do.  The series stops where what is left of it, the terms' sizes
    |c_k| (|kap_k| T)^n / n! summed (each a geometric tail once n passes |kap_k| T), is below their round-off.
    A term too fast for the series (|kap_k| T > TAYLOR_TURNS: a stiff mode, a unit's spring) is bounded alone,
    by its largest size over [0, T]; where such terms are not small, the bound is loose and the search says so."""
    nk = kap.shape[0]
    ck = c.copy()
    fastest = 0.0
    size = 0.0
    fast = 0.0
    for k in range(nk):
        if abs(kap[k]) * big_t > TAYLOR_TURNS:
            fast += abs(c[k]) * max(1.0, math.exp(kap[k].real * big_t))
            ck[k] = 0.0
        else:
            fastest = max(fastest, abs(kap[k]))
            size += abs(c[k])
    x = fastest * big_t
    bound = 0.0
    power = 1.0  # T^n / n!
    factorial = 1.0  # n!
    for n in range(TAYLOR_ORDERS):
        coef = 0.0
        terms = 0.0
        for k in range(nk):
            coef += ck[k].real
            terms += abs(ck[k])
            ck[k] *= kap[k]
        if n < 4:
            coef += factorial * p[n]
            terms += factorial * abs(p[n])
        bound += (abs(coef) + (PEAK_NOISE + (n + nk) * _EPS) * terms) * power
        power *= big_t / (n + 1)
        factorial *= n + 1
        if n >= 3 and n + 1 > 2.0 * x:  # not before the polynomial's last term is in
            # the rest: sum over n' > n of |c_k| |kap_k|^n' T^n' / n!' <= (next term) / (1 - x / (n + 2))
            rest = 0.0
            for k in range(nk):
                rest += abs(ck[k])
            rest *= power * 2.0
            if rest <= _EPS * size:
                return bound + rest + fast
    return np.inf


@njit(cache=True)
def peak_abs(kap, kpow, ek, c, p, big_t, peak, stack):
    """max(peak, max |h| over [0, T]), certified to PEAK_RTOL (see _peak_search); stack: (n, 4) work array.

    Returns the new peak, the time where it is attained (-1 if the old peak stands), whether the search
    finished (False: it gave up after many visits per extremum the fastest mode can have, and the peak is
    only a lower bound) and the slack it was certified to: |h| <= peak (1 + PEAK_RTOL) + slack over [0, T].
    """
    peak, at, status, slack = _peak_search(kap, kpow, ek, c, p, big_t, peak, stack)
    rows = stack.shape[0]
    while status == _STACK_FULL:
        # a long segment of a fast mode outgrew the stack: search again with a deeper one, rarely enough to
        # allocate it here (growing it inside the search's loop cost the common short search 5 %).  The peak
        # found so far is attained, so it stands as the new search's bound
        rows *= 4
        peak, at_again, status, again = _peak_search(kap, kpow, ek, c, p, big_t, peak, np.empty((rows, 4)))
        slack = max(slack, again)
        if at_again >= 0.0:
            at = at_again
    return peak, at, status == _FINISHED, slack


@njit(cache=True)
def _peak_search(kap, kpow, ek, c, p, big_t, peak, stack):
    """max(peak, max |h| over [0, T]), certified to PEAK_RTOL.

    Branch and bound: an interval whose bound cannot beat the running peak is
    dropped.  Where h' changes sign, its zero is refined and h evaluated
    there; around it h'' keeps its sign over a radius |h''| / M3, so h has no
    other extremum there and only the rest needs searching.  An interval where
    h' provably keeps its sign is monotone: its ends hold its extremes.
    Intervals are searched from the segment's start: a decaying transient's
    largest swing comes first and prunes the rest.
    kpow: kappa_powers of kap; ek = exp(kap T); stack: (n, 4) work array.  Returns the new peak, the time
    where it is attained (-1 if the old peak stands), _FINISHED, _GAVE_UP or _STACK_FULL, and the slack the
    intervals were dropped at: the round-off of evaluating the row, which no search can see below.
    """
    h0, d0, h1, d1 = _ends(kap, ek, c, p, big_t)
    at = -1.0
    if abs(h0) > peak:
        peak = abs(h0)
        at = 0.0
    if abs(h1) > peak:
        peak = abs(h1)
        at = big_t
    m2 = bound_tab(kpow, c, p, 2, big_t)
    if max(abs(h0), abs(h1)) + m2 * big_t * big_t / 8.0 <= peak * (1.0 + PEAK_RTOL):
        return peak, at, _FINISHED, 0.0
    m3 = bound_tab(kpow, c, p, 3, big_t)
    # h is a sum of terms of this size: a swing within its round-off of the peak cannot be told from it
    # (a row that cancels to round-off, a TMD's stroke of 1e-17 m, would otherwise be split to hmin)
    size = bound_tab(kpow, c, p, 0, big_t)
    noise = PEAK_NOISE * size
    top = _push(stack, 0, 0.0, big_t, d0, d1)
    hmin = max(big_t, 1.0) * 1e-13
    visits = 0
    visit_limit = max(PEAK_MAX_VISITS, PEAK_VISITS_PER_EXTREMUM * _extrema_bound(kap, big_t))
    # A row that cancels to far below the size of its terms (the first steps of a record from rest: a motion
    # of 1e-17 m written with terms of 1e-3 m) has curvature bounds of its terms' size, so certifying it to
    # PEAK_RTOL of its peak would split it to the round-off; a search that has spent its visits goes on,
    # as many again, certifying to PEAK_RTOL of the row's size instead: a swing no measurement resolves
    slack = noise
    widened = False
    while top > 0:
        visits += 1
        if visits > visit_limit:
            if not widened:
                widened = True
                slack = noise + PEAK_RTOL * size
                visits = 0
            elif _unsearched_bound(kap, c, p, stack, top, m2) <= peak * (1.0 + PEAK_RTOL) + slack:
                return peak, at, _FINISHED, slack  # what is left unsearched exceeds the peak by at most its bound
            elif _split_taylor_bound(kap, c, p, big_t) <= peak * (1.0 + PEAK_RTOL) + slack:
                return peak, at, _FINISHED, slack  # the whole segment is bounded by its series, to the same slack
            else:
                return peak, at, _GAVE_UP, slack
        top -= 1
        a = stack[top, 0]
        b = stack[top, 1]
        da = stack[top, 2]
        db = stack[top, 3]
        ha, _ = eval2(kap, c, p, a)
        hb, _ = eval2(kap, c, p, b)
        w = b - a
        if max(abs(ha), abs(hb)) + m2 * w * w / 8.0 <= peak * (1.0 + PEAK_RTOL) + slack or w <= hmin:
            continue
        if (da > 0.0) == (db > 0.0) and min(abs(da), abs(db)) - m3 * w * w / 8.0 > 0.0:
            continue  # monotone: the ends were counted
        if top + 2 >= stack.shape[0]:
            return peak, at, _STACK_FULL, slack  # an interval dropped here would be a maximum never looked at
        if (da > 0.0) != (db > 0.0) and da != 0.0 and db != 0.0:
            tz = _zero_of_derivative(kap, c, p, a, b, da)
            hz, _, ddz = eval3(kap, c, p, tz)
            if abs(hz) > peak:
                peak = abs(hz)
                at = tz
            rho = abs(ddz) / m3 if m3 > 0.0 else np.inf
            left = max(a, tz - rho)
            right = min(b, tz + rho)
            if left > a:
                peak, at, dl = _probe(kap, c, p, left, peak, at)
            if right < b:
                peak, at, dr = _probe(kap, c, p, right, peak, at)
                top = _push(stack, top, right, b, dr, db)
            if left > a:
                top = _push(stack, top, a, left, da, dl)
            continue
        mid = 0.5 * (a + b)
        peak, at, dmid = _probe(kap, c, p, mid, peak, at)
        top = _push(stack, top, mid, b, dmid, db)
        top = _push(stack, top, a, mid, da, dmid)
    return peak, at, _FINISHED, slack
