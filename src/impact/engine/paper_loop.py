"""Exact event-driven kernels (numba).

Between events every model of the study is linear with harmonic forcing, so the
motion on a segment is known in closed form.  We keep it in *coefficient form*

    x(tau) = Re sum_k cx[k] exp(kap[k] tau)
    y(tau) = Re sum_k cy[k] exp(kap[k] tau) + py1 tau + py2 tau^2

with tau the time since the segment started.  Slots 0..3 hold the homogeneous
modes (eigenvalues of the segment's linear system), 4 and 5 the harmonic
particular solution (exp(+-i r tau)), 6 the constant part (kap = 0).  The
polynomial in y is the free mass's ballistic flight (CID), which the
eigen-decomposition cannot express (a Jordan block at 0).

Every event (impact, release from a wall) is the first exit of a scalar
function of this form from a band.  :func:`first_exit` finds it with a
certificate: on [a, b] a function with |h''| <= M2 stays within
max(h(a), h(b)) + M2 (b-a)^2 / 8, and M2 is bounded from the coefficients
(all homogeneous modes decay, so |exp(kap tau)| <= 1).  A step is accepted
only when that bound keeps it inside the band, so an impact cannot be missed,
however briefly the trajectory touches the wall.  A crossing is refined by
safeguarded Newton once monotonicity is certified (|h'| > M2 (b-a)).

Integrals over a segment (work of the force, viscous dissipation, the square
of x for the amplitude window) are products of exponentials and are
integrated exactly.

The PID's eigen-data arrive as a tuple, the CID's as None: numba prunes the
branch that does not apply, so a CID run never compiles the pendulum path.

The loop reads the engine's one index layout (layout.py) and shares with the
scene loop the certified search (events.first_exit), the row bound and |kap|
powers (segment.bound_tab, kappa_powers), and the contact's one state machine
(contact.py): its decisions (stays, floor_decision, rebound_too_slow,
plastic_end), its transitions, which set this loop's ContactState as they set
the scene loop's RunState, the impact record and the guard on events.  What it
keeps is the one-unit algebra above, which the scene loop writes for any number
of units and so rounds differently.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact.engine import contact
from impact.engine import layout as L
from impact.engine.bundles import ContactState, PaperWork, borrowed
from impact.engine.contact import CONTACT_TOL
from impact.engine.events import first_exit
from impact.engine.segment import bound_tab, deriv_at0, kappa_powers

NT = 7  # coefficient slots, see module docstring

# the polynomial part of a row that has none: the segment's deriv_at0 takes one, and the paper loop keeps the
# ballistic flight's polynomial apart (poly), adding it where a row needs it
_NO_POLY = np.zeros(4)



# ----------------------------------------------------------------------------
# evaluation of coefficient-form functions
# ----------------------------------------------------------------------------

@njit(cache=True)
def flight_state(kap, cx, cy, py1, py2, tau, z):
    """Write (x, x', y, y') at tau into z (the sampler reads a free flight with it)."""
    _state_from(kap, np.exp(kap * tau), cx, cy, py1, py2, tau, z)


@njit(cache=True)
def _state_from(kap, eh, cx, cy, py1, py2, tau, z):
    """_state with eh = exp(kap tau) given: the segment's own exponentials."""
    x = 0.0
    v = 0.0
    y = 0.0
    w = 0.0
    for k in range(NT):
        ek = eh[k]
        a = cx[k] * ek
        b = cy[k] * ek
        x += a.real
        v += (a * kap[k]).real
        y += b.real
        w += (b * kap[k]).real
    z[0] = x
    z[1] = v
    z[2] = y + py1 * tau + py2 * tau * tau
    z[3] = w + py1 + 2.0 * py2 * tau


# ----------------------------------------------------------------------------
# segment construction
# ----------------------------------------------------------------------------

@njit(cache=True)
def _oscillator(kap, cx, x0, v0, w2, two_zeta_w, amp, r, theta0, const):
    """x'' + two_zeta_w x' + w2 x = amp sin(theta0 + r tau) + const, from (x0, v0)."""
    sigma = -0.5 * two_zeta_w
    root = np.sqrt(complex(w2 - 0.25 * two_zeta_w * two_zeta_w, 0.0))
    lp = sigma + 1j * root
    lm = sigma - 1j * root
    zp = amp / complex(w2 - r * r, two_zeta_w * r)
    ch = zp * np.exp(1j * theta0) / 2j
    kap[4] = 1j * r
    kap[5] = -1j * r
    kap[6] = 0.0
    cx[4] = ch
    cx[5] = ch.conjugate()
    cx[6] = const / w2
    xp0 = 2.0 * ch.real + const / w2
    vp0 = 2.0 * (ch * 1j * r).real
    h0 = x0 - xp0
    h1 = v0 - vp0
    cp = (h1 - lm * h0) / (lp - lm)
    kap[0] = lp
    kap[1] = lm
    kap[2] = 0.0
    kap[3] = 0.0
    cx[0] = cp
    cx[1] = h0 - cp
    cx[2] = 0.0
    cx[3] = 0.0


@njit(cache=True)
def build_free_flight(kap, cx, cy, poly, z0, t0, p, pid, fric, sigma):
    """Free flight of the damper mass from state z0 at absolute time t0.

    With friction (CID), the mass slides in direction sigma = sign(s') and a
    constant force mu a_f sigma acts on the structure, -a_f sigma on the mass.
    """
    theta0 = p[L.P_OMEGA] * t0 + p[L.P_PHI]
    if pid is None:
        if fric is None:
            _oscillator(kap, cx, z0[0], z0[1], 1.0, 2.0 * p[L.P_BETA], p[L.P_F0], p[L.P_OMEGA], theta0, 0.0)
            poly[1] = 0.0
        else:
            a_f = fric[0] * sigma
            _oscillator(kap, cx, z0[0], z0[1], 1.0, 2.0 * p[L.P_BETA], p[L.P_F0], p[L.P_OMEGA], theta0, p[L.P_MU] * a_f)
            poly[1] = -0.5 * a_f
        for k in range(NT):
            cy[k] = 0.0
        cy[6] = z0[2]
        poly[0] = z0[3]
    else:
        lam, vec, vinv, zc = pid
        ph = np.exp(1j * theta0)
        rel = np.empty(4, dtype=np.complex128)
        for i in range(4):
            rel[i] = z0[i] - (zc[i] * ph).imag
        for k in range(4):
            wk = 0.0 + 0.0j
            for i in range(4):
                wk += vinv[k, i] * rel[i]
            kap[k] = lam[k]
            cx[k] = vec[0, k] * wk
            cy[k] = vec[2, k] * wk
        kap[4] = 1j * p[L.P_OMEGA]
        kap[5] = -1j * p[L.P_OMEGA]
        kap[6] = 0.0
        cx[4] = zc[0] * ph / 2j
        cx[5] = cx[4].conjugate()
        cy[4] = zc[2] * ph / 2j
        cy[5] = cy[4].conjugate()
        cx[6] = 0.0
        cy[6] = 0.0
        poly[0] = 0.0
        poly[1] = 0.0


@njit(cache=True)
def _build_combined(kap, cx, cy, poly, z0, t0, p, offset):
    """Damper mass moving with the structure (stuck at a wall or locked, d = 0).

    The pendulum spring is internal to the combined body, so CID and PID share
    (1 + mu) x'' + 2 beta x' + x = F0 sin(.); y = x + offset.
    """
    mu = p[L.P_MU]
    theta0 = p[L.P_OMEGA] * t0 + p[L.P_PHI]
    _oscillator(kap, cx, z0[0], z0[1], 1.0 / (1.0 + mu), 2.0 * p[L.P_BETA] / (1.0 + mu),
                p[L.P_F0] / (1.0 + mu), p[L.P_OMEGA], theta0, 0.0)
    for k in range(NT):
        cy[k] = cx[k]
    cy[6] = cx[6] + offset
    poly[0] = 0.0
    poly[1] = 0.0


# ----------------------------------------------------------------------------
# event location
# ----------------------------------------------------------------------------

# ----------------------------------------------------------------------------
# exact integrals over a segment
# ----------------------------------------------------------------------------

@njit(cache=True)
def _halve(kap, c):
    """Fold each mode of an exactly conjugate pair of kap into its first slot: Re(c_j e^{kap_j t}) +
    Re(c_j+1 e^{conj(kap_j) t}) = Re((c_j + conj(c_j+1)) e^{kap_j t}), so a search on the row evaluates half
    the exponentials.  (A pair that is not exactly conjugate is left as it is.)"""
    for j in range(NT - 1):
        if kap[j].imag != 0.0 and kap[j + 1] == kap[j].conjugate() and (c[j + 1].real != 0.0
                                                                        or c[j + 1].imag != 0.0):
            c[j] += c[j + 1].conjugate()
            c[j + 1] = 0.0


@njit(cache=True)
def _int_prod0(kap, eh, ca, cb, h):
    """_int_prod over [0, h] with eh = exp(kap h): the segment's own exponentials, none evaluated here."""
    acc = 0.0
    j = 0
    while j < NT:
        # a mode and its conjugate (next slot, conjugate coefficient) give conjugate sums: Re of one, twice
        paired = j + 1 < NT and kap[j + 1] == kap[j].conjugate() and ca[j + 1] == ca[j].conjugate() \
            and kap[j].imag != 0.0
        if ca[j].real != 0.0 or ca[j].imag != 0.0:
            row = 0.0 + 0.0j
            for l in range(NT):
                if cb[l].real == 0.0 and cb[l].imag == 0.0:
                    continue
                kk = kap[j] + kap[l]
                zz = kk * h
                if zz.real * zz.real + zz.imag * zz.imag < 1e-6:  # |zz| < 1e-3
                    phi1 = h * (1.0 + zz * (0.5 + zz * (1.0 / 6.0 + zz * (1.0 / 24.0 + zz / 120.0))))
                else:
                    phi1 = (eh[j] * eh[l] - 1.0) / kk
                row += cb[l] * phi1
            acc += (2.0 if paired else 1.0) * (ca[j] * row).real
        j += 2 if paired else 1
    return acc


@njit(cache=True)
def _int_prod(kap, ca, cb, a, b):
    """Re of the integral over [a, b] of (sum ca e^{kap t})(sum cb e^{kap t})."""
    if b <= a:
        return 0.0
    h = b - a
    ea = np.empty(NT, dtype=np.complex128)
    for k in range(NT):
        ea[k] = np.exp(kap[k] * a)
    acc = 0.0 + 0.0j
    for j in range(NT):
        if ca[j].real == 0.0 and ca[j].imag == 0.0:
            continue
        for l in range(NT):
            if cb[l].real == 0.0 and cb[l].imag == 0.0:
                continue
            kk = kap[j] + kap[l]
            zz = kk * h
            if abs(zz) < 1e-3:
                phi1 = h * (1.0 + zz * (0.5 + zz * (1.0 / 6.0 + zz * (1.0 / 24.0 + zz / 120.0))))
            else:
                phi1 = (np.exp(zz) - 1.0) / kk
            acc += ca[j] * cb[l] * ea[j] * ea[l] * phi1
    return acc.real


@njit(cache=True)
def _energy(z, p):
    mu = p[L.P_MU]
    wp = p[L.P_WP]
    s = z[2] - z[0]
    return 0.5 * (z[1] * z[1] + z[0] * z[0] + mu * z[3] * z[3] + mu * wp * wp * s * s)


# ----------------------------------------------------------------------------
# contact resolution
# ----------------------------------------------------------------------------

@njit(cache=True)
def _stays_stuck(kap, cx, p, side, a_f, cq, pq):
    """Whether the wall on `side` keeps holding the damper mass (cq, pq: scratch for its contact-force row).

    The contact force on the damper is N = mu (x'' + wp^2 side d/2) and the
    wall on `side` can only push inwards; friction (CID) can add up to mu a_f
    either way: the mass stays while q = side*x'' + wp^2 d/2 - a_f <= 0, which contact.stays decides.
    """
    for k in range(NT):
        cq[k] = side * cx[k] * kap[k] * kap[k]
    _poly4(pq, 0.0, 0.0)
    pq[0] = p[L.P_WP] ** 2 * 0.5 * p[L.P_GAP] - a_f
    return contact.stays(kap, cq, pq)


@njit(cache=True)
def _apply_impact(z, side, p, diag):
    """Newton impact (Eq. 3), then stick if the rebound is below threshold.

    Returns True when the relative velocity was reset to zero (sticking
    candidate).  Momentum is conserved to round-off; losses are booked.
    """
    mu = p[L.P_MU]
    e = p[L.P_E]
    vm = z[1]
    wm = z[3]
    srel = wm - vm
    z[1] = ((1.0 - mu * e) * vm + mu * (1.0 + e) * wm) / (1.0 + mu)
    z[3] = ((1.0 + e) * vm + (mu - e) * wm) / (1.0 + mu)
    red = 0.5 * mu / (1.0 + mu)
    diag[L.D_IMPLOSS] += red * (1.0 - e * e) * srel * srel
    z[2] = z[0] + side * 0.5 * p[L.P_GAP]
    if abs(z[3] - z[1]) < p[L.P_VSTICK]:
        _stick(z, p, diag)
        return True
    return False


@njit(cache=True)
def _stick(z, p, diag):
    """Perfectly plastic end of a rebound (contact.plastic_end), the loss booked; the structure's mass is 1."""
    vc, lost = contact.plastic_end(p[L.P_MU], z[3], 1.0, z[1])
    diag[L.D_IMPLOSS] += lost
    z[1] = vc
    z[3] = vc


@njit(cache=True)
def _floor_decision(kap, cx, a_f, cq, pq):
    """contact.floor_decision for the paper's damper: the combined body's x'' against a_f (the friction force
    that drags the mass along is m x''); cq, pq: scratch for that row."""
    for k in range(NT):
        cq[k] = cx[k] * kap[k] * kap[k]
    _poly4(pq, 0.0, 0.0)
    return contact.floor_decision(kap, cq, pq, a_f)


@njit(cache=True)
def _poly4(pp, p1, p2):
    pp[0] = 0.0
    pp[1] = p1
    pp[2] = p2
    pp[3] = 0.0


@njit(cache=True, inline='always')
def _event_kind(ev_kind, mode):
    """The scene loop's name of this loop's event (layout.EV_*): its ev_kind 2 ends a slide, 1 is whatever
    the mode's search looked for."""
    if ev_kind == 2:
        return L.EV_SLIDE_STOP
    if mode == L.MODE_STUCK:
        return L.EV_RELEASE
    if mode == L.MODE_FLOOR:
        return L.EV_FLOOR_EXIT
    return L.EV_WALL


def contact_code(mode, side, sigma):
    """One integer for a contact state (mode, side, sigma): what a run starts from and ends in."""
    return mode + 10 * (side + 1) + 100 * (sigma + 1)


def decode_contact(code):
    """The contact state (mode, side, sigma) that contact_code made the integer of."""
    return code % 10, (code % 100) // 10 - 1, code // 100 - 1


# the kernels' copy; Python calls contact_code, so importing a module that only names a state loads no
# compiled code (a cached load costs about 0.1 s, and plots and the workflow's start-up need none)
encode_contact = njit(cache=True)(contact_code)
_decode_contact = njit(cache=True, inline='always')(decode_contact)


# ----------------------------------------------------------------------------
# the run: a loop over segments, each read as its named steps
# ----------------------------------------------------------------------------

@njit(cache=True, inline='always')
def _build_motion(w, t, pid, fric, a_f):
    """The segment's motion in coefficient form for the contact mode; True when the contact changes before the
    segment starts (the floor lets the mass slide, or the wall no longer holds it): the loop then starts again."""
    kap, cx, cy, poly, z, p, cq, pp, c = w.kap, w.cx, w.cy, w.poly, w.z, w.p, w.cq, w.pp, w.c
    mode = c.mode[0]
    if mode == L.MODE_FREE:
        build_free_flight(kap, cx, cy, poly, z, t, p, pid, fric, c.sigma[0])
    elif mode == L.MODE_FLOOR:
        _build_combined(kap, cx, cy, poly, z, t, p, z[2] - z[0])
        if fric is not None:
            slide = _floor_decision(kap, cx, a_f, cq, pp)
            if slide != 0:
                contact.start_slide(c, 0, slide)
                return True
    else:
        side = c.side[0]
        half = 0.5 * p[L.P_GAP]
        _build_combined(kap, cx, cy, poly, z, t, p, side * half if mode == L.MODE_STUCK else 0.0)
        if mode == L.MODE_STUCK and not _stays_stuck(kap, cx, p, side, a_f, cq, pp):
            contact.leave_wall(c, 0, fric is not None)
            return True
    return False


@njit(cache=True, inline='always')
def _velocity_and_powers(w):
    """The velocity row x' and, for a new set of exponents (a new contact mode), their |kap|^n for the bounds."""
    kap, cx, cv, kpow, kap_powered = w.kap, w.cx, w.cv, w.kpow, w.kap_powered
    for k in range(NT):
        cv[k] = cx[k] * kap[k]
        if kap[k] != kap_powered[k]:
            kappa_powers(kap, kpow)
            kap_powered[:] = kap


@njit(cache=True, inline='always')
def _search_event(w, fric, a_f, tau_max):
    """The next event of the contact mode, certified (events.first_exit), into w.ev (time, side, grazing passes,
    steps).  Returns its kind: 1 the mode's own (an impact, the wall letting go, the floor letting the mass
    slide), 2 a slide coming to rest."""
    kap, kpow, cx, cy, cs, cq, poly, pp, p, c, ev = w.kap, w.kpow, w.cx, w.cy, w.cs, w.cq, w.poly, w.pp, w.p, w.c, w.ev
    mode = c.mode[0]
    d = p[L.P_GAP]
    half = 0.5 * d
    if mode == L.MODE_FREE:
        for k in range(NT):
            cs[k] = cy[k] - cx[k]
        _halve(kap, cs)
        delta = CONTACT_TOL * (bound_tab(kpow, cs, _NO_POLY, 0, 0.0) + d)
        _poly4(pp, poly[0], poly[1])
        first_exit(kap, kpow, cs, pp, -half, half, tau_max, c.escape[0], delta, ev)
        if fric is not None:
            return _search_slide_stop(w, tau_max)
    elif mode == L.MODE_STUCK:
        side = c.side[0]
        for k in range(NT):
            cq[k] = side * cx[k] * kap[k] * kap[k]
        _halve(kap, cq)
        level = -p[L.P_WP] ** 2 * half + a_f
        delta = CONTACT_TOL * (bound_tab(kpow, cq, _NO_POLY, 0, 0.0) + abs(level))
        # just stuck with the contact force at round-off from its limit: the
        # force is known to move away from it (see _stays_stuck)
        q0 = deriv_at0(kap, cq, _NO_POLY, 0)
        esc = 1 if level - q0 < delta else 0
        _poly4(pp, 0.0, 0.0)
        first_exit(kap, kpow, cq, pp, -np.inf, level, tau_max, esc, delta, ev)
    elif mode == L.MODE_FLOOR:
        for k in range(NT):
            cq[k] = cx[k] * kap[k] * kap[k]
        _halve(kap, cq)
        delta = CONTACT_TOL * (bound_tab(kpow, cq, _NO_POLY, 0, 0.0) + a_f)
        q0 = deriv_at0(kap, cq, _NO_POLY, 0)
        esc = 0
        if a_f - abs(q0) < delta:
            esc = 1 if q0 > 0.0 else -1
        _poly4(pp, 0.0, 0.0)
        first_exit(kap, kpow, cq, pp, -a_f, a_f, tau_max, esc, delta, ev)
    else:
        ev[0] = np.inf
        ev[1] = 0.0
        ev[2] = 0.0
        ev[3] = 0.0
    return 1


@njit(cache=True, inline='always')
def _search_slide_stop(w, tau_max):
    """A sliding mass's slide stopping (sigma s' > 0 while it slides, 0 where it stops) before the gap's event:
    2 if it comes first (w.ev then holds it), else 1."""
    kap, kpow, cs, cq, poly, pp, c, ev, ev2 = w.kap, w.kpow, w.cs, w.cq, w.poly, w.pp, w.c, w.ev, w.ev2
    sigma = c.sigma[0]
    for k in range(NT):
        cq[k] = sigma * cs[k] * kap[k]
    cq[6] += sigma * poly[0]
    dv = CONTACT_TOL * (bound_tab(kpow, cq, _NO_POLY, 0, 0.0) + 2.0 * abs(poly[1]))
    _poly4(pp, 2.0 * sigma * poly[1], 0.0)
    first_exit(kap, kpow, cq, pp, 0.0, np.inf, min(ev[0], tau_max), c.escape_v[0], dv, ev2)
    w.diag[L.D_STEPS] += ev2[3]
    if ev2[0] < ev[0]:
        ev[0] = ev2[0]
        ev[1] = 0.0
        return 2
    return 1


@njit(cache=True, inline='always')
def _advance(w, fric, a_f, t, tau):
    """Move the state to the segment's end, tau after t, and book its exact integrals: the force's work, the
    viscous loss, x^2 over the window, the time in contact, the friction's work; the energy's high mark."""
    kap, eh, cx, cy, cv, cf, poly, z, p, c, ev, diag = (w.kap, w.eh, w.cx, w.cy, w.cv, w.cf, w.poly, w.z, w.p, w.c,
                                                        w.ev, w.diag)
    diag[L.D_SEGMENTS] += 1.0
    diag[L.D_GRAZE] += ev[2]
    diag[L.D_STEPS] += ev[3]
    theta0 = p[L.P_OMEGA] * t + p[L.P_PHI]
    cf[4] = p[L.P_F0] * np.exp(1j * theta0) / 2j
    cf[5] = cf[4].conjugate()
    for k in range(NT):
        if k > 0 and kap[k] == kap[k - 1].conjugate():
            eh[k] = eh[k - 1].conjugate()  # exp(conj(z)) = conj(exp(z)): one exponential per pair
        else:
            eh[k] = np.exp(kap[k] * tau)
    diag[L.D_WORK] += _int_prod0(kap, eh, cf, cv, tau)
    diag[L.D_VISC] += 2.0 * p[L.P_BETA] * _int_prod0(kap, eh, cv, cv, tau)
    t_win = p[L.P_TWIN]
    if t + tau > t_win:
        if t >= t_win:
            diag[L.D_X2WIN] += _int_prod0(kap, eh, cx, cx, tau)
        else:
            diag[L.D_X2WIN] += _int_prod(kap, cx, cx, t_win - t, tau)
    if c.mode[0] != L.MODE_FREE:
        diag[L.D_STUCKTIME] += tau
    s_start = z[2] - z[0]
    _state_from(kap, eh, cx, cy, poly[0], poly[1], tau, z)
    e_now = _energy(z, p)
    if e_now > diag[L.D_EMAX]:
        diag[L.D_EMAX] = e_now
    if fric is not None:
        if c.mode[0] == L.MODE_FREE:
            # s' keeps its sign on a sliding segment: the work is exact
            diag[L.D_FRICTION] += p[L.P_MU] * a_f * c.sigma[0] * (z[2] - z[0] - s_start)


@njit(cache=True, inline='always')
def _book_stop(diag, stop, ev_kind, mode, ev_side):
    """Why and where the run stopped at an event cap or the stall guard (layout.D_STOP_*)."""
    diag[L.D_CAP] = stop
    diag[L.D_STOP_ELEMENT] = 0.0  # the one unit
    diag[L.D_STOP_EVENT] = _event_kind(ev_kind, mode)
    diag[L.D_STOP_SIDE] = ev_side


@njit(cache=True, inline='always')
def _resolve_event(w, t, pid, fric, a_f, ev_kind, ev_side, irec):
    """The contact's answer to the event at t: a slide comes to rest or starts, the wall lets go, or the mass
    strikes or touches wall ev_side (then the impact, whether the mass rests on the wall and whether the wall holds
    it, and its record).  Returns the number of impact records written."""
    z, p, c, diag, rec = w.z, w.p, w.c, w.diag, w.rec
    half = 0.5 * p[L.P_GAP]
    mode = c.mode[0]
    if fric is not None:
        if ev_kind == 2:
            # the slide ends: the floor holds the mass or it slides back
            z[3] = z[1]
            contact.rest_on_floor(c, 0)
            return irec
        if mode == L.MODE_FLOOR:
            # the floor can no longer drag the mass along: it slides
            z[3] = z[1]
            contact.start_slide(c, 0, -ev_side)
            return irec
    if mode == L.MODE_STUCK:
        # release: the wall stops holding the mass, which leaves with s' = 0
        z[2] = z[0] + c.side[0] * half
        z[3] = z[1]
        contact.leave_wall(c, 0, fric is not None)
        return irec
    # read off its own one-unit rows in model units, whose round-off is a few ulps of the motion: none is
    # allowed for
    contact.note_penetration(diag, abs(z[2] - z[0]) - half, 0.0)
    approach = ev_side * (z[3] - z[1])
    vm = z[1]
    wm = z[3]
    if approach <= 0.0:
        # touched within contact tolerance while already separating: at a speed below the sticking one it rests
        # there, else it is judged as a rebound, which rests on the wall if it cannot clear the tolerance (the
        # scene loop decides the same)
        z[2] = z[0] + ev_side * half
        resting = abs(z[3] - z[1]) < p[L.P_VSTICK]
        if resting:
            _stick(z, p, diag)
        _settle_at_wall(w, t, pid, fric, a_f, ev_side, resting)
        return irec
    diag[L.D_IMPACTS] += 1.0
    if t >= p[L.P_TWIN]:
        diag[L.D_IMPACTS_WIN] += 1.0
    _settle_at_wall(w, t, pid, fric, a_f, ev_side, _apply_impact(z, ev_side, p, diag))
    if irec < rec.shape[0]:
        # Newton's impulse alone, as solve_impulses gives it in the scene loop
        impulse = p[L.P_MU] * (1.0 + p[L.P_E]) * approach / (1.0 + p[L.P_MU])
        contact.record_impact(rec[irec], t, 0.0, c.side[0], z[0], (vm, wm), (z[1], z[3]), c.mode[0] == L.MODE_STUCK,
                              impulse)
        irec += 1
    return irec


@njit(cache=True, inline='always')
def _settle_at_wall(w, t, pid, fric, a_f, side, resting):
    """The mass's contact after it struck or touched wall `side` (resting: it already moves with the structure): a
    rebound too slow to clear the contact tolerance ends plastically (contact.rebound_too_slow), and a mass resting
    on the wall is held or let go (contact.stays)."""
    kap, kpow, cx, cy, cs, cq, pp, poly, z, p, c, diag = (w.kap, w.kpow, w.cx, w.cy, w.cs, w.cq, w.pp, w.poly, w.z,
                                                          w.p, w.c, w.diag)
    contact.meet_wall(c, 0, side, fric is not None)
    if not resting:
        build_free_flight(kap, cx, cy, poly, z, t, p, pid, fric, c.sigma[0])
        for k in range(NT):
            cs[k] = cy[k] - cx[k]
        push = side * (deriv_at0(kap, cs, _NO_POLY, 2) + 2.0 * poly[1])
        tol = CONTACT_TOL * (bound_tab(kpow, cs, _NO_POLY, 0, 0.0) + p[L.P_GAP])
        if contact.rebound_too_slow(push, z[3] - z[1], tol):
            _stick(z, p, diag)
            resting = True
    if not resting:
        contact.rebound(c, 0)
        return
    _build_combined(kap, cx, cy, poly, z, t, p, side * (0.5 * p[L.P_GAP]))
    if _stays_stuck(kap, cx, p, side, a_f, cq, pp):
        contact.hold(c, 0)
        diag[L.D_STICKS] += 1.0
    else:
        contact.leave_wall(c, 0, fric is not None)


@njit(cache=True, inline='always')
def _initial_contact(c, code_init, z, p, fric):
    """The contact state a run starts in, into c, from its code (encode_contact) and state: no gap locks the
    mass; a state just after an impact (a closed-form orbit) escapes its wall; with friction, a mass moving with
    the floor rests on it, and one that moves relative to it slides."""
    mode, side, sigma = _decode_contact(code_init)
    c.mode[0] = mode
    c.side[0] = side
    c.sigma[0] = sigma
    d = p[L.P_GAP]
    if d == 0.0:
        c.mode[0] = L.MODE_LOCKED
    if c.mode[0] == L.MODE_FREE and side != 0 and abs(z[2] - z[0]) >= 0.5 * d * (1.0 - CONTACT_TOL) and d > 0.0:
        c.escape[0] = side
    if fric is not None:
        if c.mode[0] == L.MODE_FREE and z[3] == z[1]:
            c.mode[0] = L.MODE_FLOOR
        elif c.mode[0] == L.MODE_FREE and c.sigma[0] == 0:
            contact.slide_with(c, 0, z[3] - z[1])


# the run's workspace: complex rows over the coefficient slots, its real vectors and its contact state's integers,
# sliced into views
W_KAP, W_CX, W_CY, W_CS, W_CV, W_CQ, W_CF, W_EH, W_POWERED = range(9)
NROWS = 9
V_POLY, V_PP, V_EV, V_EV2, NVEC = 0, 2, 6, 10, 14
NCONTACT = len(ContactState._fields)


@njit(cache=True)
def run(p, z_init, code_init, pid, fric, rec, diag, z_out):
    """One run from absolute time p[L.P_T0] to p[L.P_TEND] (p: layout.NPAR_PAPER parameters).

    z_init: (x, x', y, y'); code_init: initial contact state (encode_contact).
    pid: PID eigen-data or None (CID); fric: (a_f,) or None (frictionless):
    None prunes that path at compile time.  rec: (n, layout.NREC) impact records
    (n may be 0).  diag: layout.NDIAG diagnostics (zeroed here).  z_out: final state.
    Returns the final contact code, for continuation runs.
    """
    rows = np.zeros((NROWS, NT), dtype=np.complex128)
    rows[W_POWERED, :] = np.nan
    owners = (rows, np.zeros((5, NT)), np.zeros(NVEC), np.zeros(5), np.zeros(NCONTACT, dtype=np.int64))
    return _loop(p, z_init, code_init, pid, fric, rec, diag, z_out, owners)


@njit(cache=True)
def _loop(p, z_init, code_init, pid, fric, rec, diag, z_out, owners):
    """run's loop over segments, in the workspace run allocated and holds while this runs (owners: the complex
    rows, the |kap| powers, the real vectors, the event guard's clock and the contact state).  Every array is
    taken borrowed (bundles.borrowed: no reference of its own), so handing the bundle to a step costs no
    reference count: the counts were a quarter of a run when the loop was written as these steps."""
    rows, kpow, vec, clock, c = owners
    rows, vec, clock, c = borrowed(rows), borrowed(vec), borrowed(clock), borrowed(c)
    state = ContactState(c[0:1], c[1:2], c[2:3], c[3:4], c[4:5])
    w = PaperWork(rows[W_KAP], rows[W_CX], rows[W_CY], rows[W_CS], rows[W_CV], rows[W_CQ], rows[W_CF], rows[W_EH],
                  borrowed(kpow), rows[W_POWERED], vec[V_POLY:V_PP], vec[V_PP:V_EV], vec[V_EV:V_EV2],
                  vec[V_EV2:NVEC], state, borrowed(p), borrowed(z_out), borrowed(diag), borrowed(rec))
    z, ev, c, diag = w.z, w.ev, w.c, w.diag
    for i in range(L.NDIAG):
        diag[i] = 0.0
    for i in range(4):
        z[i] = z_init[i]
    t = p[L.P_T0]
    t_end = p[L.P_TEND]
    a_f = 0.0
    if fric is not None:
        a_f = fric[0]
    _initial_contact(c, code_init, z, p, fric)
    diag[L.D_E0] = _energy(z, p)
    diag[L.D_EMAX] = diag[L.D_E0]
    clock[0] = math.floor(t / p[L.P_PERIOD])  # contact.event_cap_reached's
    clock[2] = t
    irec = 0
    while t < t_end:
        tau_max = t_end - t
        if _build_motion(w, t, pid, fric, a_f):
            continue
        _velocity_and_powers(w)
        ev_kind = _search_event(w, fric, a_f, tau_max)
        tau = min(ev[0], tau_max)
        _advance(w, fric, a_f, t, tau)
        t = t + tau
        c.escape[0] = 0
        c.escape_v[0] = 0
        if ev[0] > tau_max:
            break
        stop = contact.event_cap_reached(t, p, clock)  # the caps on events per period and per run, and the stall guard
        if stop != 0:
            _book_stop(diag, stop, ev_kind, c.mode[0], ev[1])
            break
        irec = _resolve_event(w, t, pid, fric, a_f, ev_kind, int(ev[1]), irec)
    diag[L.D_E1] = _energy(z, p)
    diag[L.D_NREC] = irec
    diag[L.D_TEND] = t
    return encode_contact(c.mode[0], c.side[0], c.sigma[0])
