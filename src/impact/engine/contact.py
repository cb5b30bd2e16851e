"""Contact of the damper units with their walls: impacts, sticking, release.

Impacts on one floor at one instant are solved together.  Each contact k
(a unit hitting the wall on side_k, or a unit resting against a wall of the
same floor) gets an impulse P_k >= 0 pushing it off its wall; its floor gets
the opposite.  With u_k = side_k (w_k - v_floor) the approach speed,

    u_k+ = u_k- - sum_l W_kl P_l,   W_kl = delta_kl / m_k + side_k side_l / M_floor,

and Newton's law u_k+ = -e_k u_k- holds on every contact with P_k > 0, while a
contact with P_k = 0 separates at least that fast.  This linear
complementarity problem is solved by an active set; n identical units
hitting together get identical impulses and move as one unit of their total
mass.  Floors do not exchange impulses (the storeys are springs), so floors
are independent.

Both loops of the engine share from here what they decide at an event and what
follows from it, one state machine of a unit's contact:

- the decisions: whether a wall keeps holding a unit (stays), whether friction
  holds it on its floor (floor_decision), whether a rebound is too slow to
  resolve (rebound_too_slow) and its plastic end then (plastic_end);
- the transitions between the modes (layout.MODE_*), each a function over a
  unit's row of a contact state (any bundle with the arrays mode, side, sigma,
  escape, escape_v: the scene loop's RunState, the paper loop's ContactState of
  its one unit): meet_wall, leave_wall, rebound, hold, start_slide,
  rest_on_floor, slip, slide_with;
- an impact's record (record_impact), a wall event's penetration
  (note_penetration) and the guard on a run's events (event_cap_reached).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact.engine import layout as L
from impact.engine.layout import MODE_FLOOR, MODE_FREE, MODE_LOCKED, MODE_STUCK

#: relative velocity below which a rebound is treated as sticking, in units of the load's velocity scale
#: (F0/K * omega for the paper's system); far below any resolved rebound
STICK_VELOCITY = 1e-8


def free_vibration_stick(q, v, omega1: float) -> float:
    """A free vibration's stick velocity: STICK_VELOCITY in units of the velocity scale omega1 X of where it starts,
    X its largest displacement or velocity over omega1 (both loops; 0 at rest)."""
    return STICK_VELOCITY * omega1 * max(float(np.max(np.abs(q))), float(np.max(np.abs(v))) / omega1)


_ZERO_TOL = 1e-10  # relative size below which a derivative counts as zero
#: contact tolerance of both loops, relative to the size of the gap function: a unit within it of its wall is on
#: it, a relative speed within it of the row's scale is zero
CONTACT_TOL = 1e-12


@njit(cache=True)
def floor_mass(f, building, units, mode):
    """Mass that moves with floor f under an impulse: the floor and its locked units."""
    m = building.mass[f]
    ufloor, um = units.floor, units.mass
    for j in range(um.shape[0]):
        if ufloor[j] == f and mode[j] == MODE_LOCKED:
            m += um[j]
    return m


@njit(cache=True)
def solve_impulses(u, minv, side, e, count, m_floor, impulse):
    """Active-set solution of the impact LCP on one floor (see module docstring).

    Contacts come in groups of count[k] identical units (same side, mass,
    restitution and approach speed, bit for bit): a group shares one impulse,
    so identical units stay identical to the last bit.
    """
    n = u.shape[0]
    if n == 1:
        # one group: Newton's law with the reduced mass, or no impulse at all
        impulse[0] = max((1.0 + e[0]) * u[0] / (minv[0] + count[0] / m_floor), 0.0)
        return
    active = np.ones(n, dtype=np.bool_)
    for _ in range(4 * n + 4):
        idx = np.nonzero(active)[0]
        na = idx.shape[0]
        for k in range(n):
            impulse[k] = 0.0
        if na > 0:
            w = np.empty((na, na))
            rhs = np.empty(na)
            for a in range(na):
                k = idx[a]
                rhs[a] = (1.0 + e[k]) * u[k]
                for b in range(na):
                    l = idx[b]
                    w[a, b] = side[k] * side[l] * count[l] / m_floor + (minv[k] if k == l else 0.0)
            sol = np.linalg.solve(w, rhs)
            worst = 0
            most = 0.0
            for a in range(na):
                if sol[a] < most:
                    most = sol[a]
                    worst = idx[a]
            if most < 0.0:
                active[worst] = False
                continue
            for a in range(na):
                impulse[idx[a]] = sol[a]
        # a contact left out must separate at least as fast as Newton's law says
        added = False
        for k in range(n):
            if active[k]:
                continue
            uk = u[k] - impulse[k] * minv[k]
            for l in range(n):
                uk -= side[k] * side[l] * count[l] * impulse[l] / m_floor
            if uk > -e[k] * u[k] * (1.0 + 1e-12) + 1e-300:
                if u[k] > 0.0:
                    active[k] = True
                    added = True
        if not added:
            return


@njit(cache=True)
def plastic_end(m_unit, w, m_floor, v):
    """A rebound too slow to resolve ends plastically: the unit (mass m_unit, velocity w) and all that moves
    with its floor (m_floor, v) take their common velocity, momentum kept.  Returns that velocity and the
    energy lost."""
    rel = w - v
    return (m_floor * v + m_unit * w) / (m_floor + m_unit), 0.5 * m_unit * m_floor / (m_unit + m_floor) * rel * rel


@njit(cache=True)
def stuck_row(kap, C, P, f, side, acc0, acc1, level, cq, pq):
    """Contact-force row of a unit resting on wall `side` of floor f: it stays while q <= 0.

    q = side (x_f'' - a(tau)) + level, with a = acc0 + acc1 tau the unit's load
    acceleration and level = wp^2 d/2 - a_f (spring pull at the wall, friction).
    """
    for k in range(kap.shape[0]):
        cq[k] = side * C[f, k] * kap[k] * kap[k]
    pq[0] = side * (2.0 * P[f, 2] - acc0) + level
    pq[1] = side * (6.0 * P[f, 3] - acc1)
    pq[2] = 0.0
    pq[3] = 0.0


@njit(cache=True)
def floor_row(kap, C, P, f, acc0, acc1, cq, pq):
    """x_f'' - a(tau): the friction force per unit mass needed to drag a unit along."""
    stuck_row(kap, C, P, f, 1.0, acc0, acc1, 0.0, cq, pq)


@njit(cache=True)
def derivatives_at0(kap, c, p):
    """A row's value and first three derivatives at tau = 0 (as segment.deriv_at0 sums them), and beside each
    the sum of its terms' sizes, the scale a zero test compares it with: two 4-tuples, in one pass.

    The sizes take sqrt(re^2 + im^2) and a running product of |kap|, not abs() and a power: a contact decision
    runs on every stick and every slide's end, and hypot and pow made them the costliest part of it.
    """
    q0 = q1 = q2 = q3 = 0.0
    s0 = s1 = s2 = s3 = 0.0
    for k in range(kap.shape[0]):
        z = c[k]
        if z.real == 0.0 and z.imag == 0.0:
            continue
        kk = kap[k]
        size = math.sqrt(z.real * z.real + z.imag * z.imag)
        grow = math.sqrt(kk.real * kk.real + kk.imag * kk.imag)
        q0 += z.real
        s0 += size
        z = z * kk
        q1 += z.real
        s1 += size * grow
        z = z * kk
        q2 += z.real
        s2 += size * grow * grow
        z = z * kk
        q3 += z.real
        s3 += size * grow * grow * grow
    return ((q0 + p[0], q1 + p[1], q2 + 2.0 * p[2], q3 + 6.0 * p[3]),
            (s0 + abs(p[0]), s1 + abs(p[1]), s2 + 2.0 * abs(p[2]), s3 + 6.0 * abs(p[3])))


@njit(cache=True)
def stays(kap, cq, pq):
    """Whether q <= 0 holds just after tau = 0 (first clearly non-zero derivative)."""
    q, scale = derivatives_at0(kap, cq, pq)
    for n in range(4):
        if abs(q[n]) > _ZERO_TOL * scale[n]:
            return q[n] < 0.0
    return True


@njit(cache=True)
def slide_decision(q, scale, a_f, zero_tol):
    """Friction, s' = 0 away from the walls: stick to the floor (0) or slide (sigma = -+1).

    q[0] is the acceleration the floor's friction must match (it can give at most a_f) and q[1:] its
    next derivatives at this instant, scale[n] a bound of each.  A tie within zero_tol is decided by the
    first derivative that is not zero.  If the drive is harder to the right, the mass lags behind and
    slides with s' < 0.
    """
    x2 = q[0]
    tol = zero_tol * (scale[0] + a_f)
    if x2 > a_f + tol:
        return -1
    if x2 < -a_f - tol:
        return 1
    if abs(x2) < a_f - tol:
        return 0
    sgn = 1 if x2 > 0.0 else -1
    for n in range(1, len(q)):
        if abs(q[n]) > zero_tol * scale[n]:
            return -sgn if sgn * q[n] > 0.0 else 0
    return 0


@njit(cache=True)
def floor_decision(kap, cq, pq, a_f):
    """slide_decision for a unit on a floor: sticking needs |x_f'' - a| <= a_f (row cq, pq)."""
    q, scale = derivatives_at0(kap, cq, pq)
    return slide_decision(q, scale, a_f, _ZERO_TOL)


@njit(cache=True)
def rebound_too_slow(push, rebound, tol):
    """Whether a rebound at relative speed `rebound`, pushed back at `push` (the gap row's second derivative
    towards the wall), has an excursion v^2 / (2 push) within the contact tolerance `tol`: then it cannot be
    resolved, and the unit rests on the wall."""
    return push > 0.0 and rebound * rebound < 2.0 * tol * push


# the state machine's transitions: each sets a unit's contact state (mode, wall side, slide sign, and the escapes of
# its next searches from the boundary it starts on), the same in both loops

@njit(cache=True)
def meet_wall(st, j, side, friction):
    """Unit j meets the wall on `side` (it strikes or touches it, or the wall moves away from it): with friction,
    a slide from here can only be away from that wall."""
    st.side[j] = side
    if friction:
        st.sigma[j] = -side


@njit(cache=True)
def leave_wall(st, j, friction):
    """The wall on st.side[j] stops holding unit j, which leaves it at its floor's speed: free, its gap search
    escaping that wall; with friction it slides away from the wall, its slide search escaping s' = 0."""
    st.mode[j] = MODE_FREE
    st.escape[j] = st.side[j]
    if friction:
        st.sigma[j] = -st.side[j]
        st.escape_v[j] = -1


@njit(cache=True)
def rebound(st, j):
    """Unit j rebounds from the wall on st.side[j]: free, its gap search escaping that wall."""
    st.mode[j] = MODE_FREE
    st.escape[j] = st.side[j]


@njit(cache=True)
def hold(st, j):
    """The wall on st.side[j] holds unit j: it moves with its floor until the wall lets go."""
    st.mode[j] = MODE_STUCK


@njit(cache=True)
def start_slide(st, j, sigma):
    """Friction stops holding unit j on its floor: it slides with sign sigma, its slide search escaping s' = 0."""
    st.mode[j] = MODE_FREE
    st.sigma[j] = sigma
    st.escape_v[j] = -1


@njit(cache=True)
def slide_with(st, j, rel):
    """Friction opposes unit j's motion rel relative to its floor, which is not zero: it slides with the sign of rel,
    its slide search starting away from s' = 0."""
    st.sigma[j] = 1 if rel > 0.0 else -1
    st.escape_v[j] = 0


@njit(cache=True)
def slip(st, j, rel):
    """Friction held unit j on its floor, and the floor's velocity jumped under it (an impulse friction cannot pass
    on): it slides, at rel relative to the floor."""
    st.mode[j] = MODE_FREE
    slide_with(st, j, rel)


@njit(cache=True)
def rest_on_floor(st, j):
    """Unit j's slide stops: friction holds it on its floor, if it can (floor_decision)."""
    st.mode[j] = MODE_FLOOR


@njit(cache=True)
def record_impact(row, t, unit, side, x, before, after, stuck, impulse):
    """One impact's record (layout.R_*): its time, unit and wall, the floor's place, the floor's and the unit's
    velocities before and after (two pairs), whether the unit stuck, and Newton's impulse (a plastic end is not in
    it)."""
    row[L.R_T] = t
    row[L.R_UNIT] = unit
    row[L.R_SIDE] = side
    row[L.R_X] = x
    row[L.R_V0], row[L.R_W0] = before
    row[L.R_V1], row[L.R_W1] = after
    row[L.R_STUCK] = 1.0 if stuck else 0.0
    row[L.R_IMPULSE] = impulse


@njit(cache=True)
def note_penetration(diag, pen, roundoff):
    """Keep a wall event's penetration pen (how far past its wall the unit is when the event is applied): the
    deepest (layout.D_PEN), and the deepest beyond `roundoff`, the round-off of the positions it is read from
    (layout.D_PEN_EXCESS).  An event is located on its gap row to that row's round-off, which an ill-conditioned
    modal basis (a post-yield stiffness near zero beside pendulums) makes thousands of ulps of the motion: what
    the location promises is the excess."""
    if pen > diag[L.D_PEN]:
        diag[L.D_PEN] = pen
    if pen - roundoff > diag[L.D_PEN_EXCESS]:
        diag[L.D_PEN_EXCESS] = pen - roundoff


STALL_EVENTS, STALL_SPAN = 1000, 1e-9  # this many events within this fraction of a period: no progress


@njit(cache=True)
def event_cap_reached(t, p, clock):
    """Count the event in its period and in the run; layout.STOP_CAP past the cap per period, layout.STOP_STALL
    when STALL_EVENTS events in a row took less than STALL_SPAN of a period (a loop that makes no progress: a bug,
    since chatter is resolved by sticking), layout.STOP_BUDGET past the run's event budget, else 0.

    clock: the period index, its events so far, the time and count of the last stall check, the run's events.
    """
    pi_now = math.floor(t / p[L.P_PERIOD])
    if pi_now != clock[0]:
        clock[0] = pi_now
        clock[1] = 0.0
    clock[1] += 1.0
    clock[3] += 1.0
    clock[4] += 1.0
    if clock[3] >= STALL_EVENTS:
        if t - clock[2] < STALL_SPAN * p[L.P_PERIOD]:
            return L.STOP_STALL
        clock[2] = t
        clock[3] = 0.0
    if clock[1] > p[L.P_MAXEV]:
        return L.STOP_CAP
    return L.STOP_BUDGET if clock[4] > p[L.P_MAXEV_RUN] else 0
