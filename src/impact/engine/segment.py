"""Closed-form flow of a scene between events.

A *configuration* is the set of damper units that move with their floor
(stuck at a wall, locked with d = 0, or dragged by friction).  Those units
add their mass to the floor; a PID's or TMD's spring then becomes internal.
The other units with a spring (PID, TMD) are degrees of freedom of the linear
system; a free CID unit has no spring, so its flight is a polynomial and it
does not enter the eigen-problem at all.  Each configuration's eigen-data
are computed once and kept in a small cache (slots, replaced in turn).

The load on a segment is either harmonic (two slots exp(+-i Omega tau) at the
end of the coefficient vector) or a polynomial of degree 1 (a piecewise-linear
record between two samples), whose particular solution is a polynomial too:
q_p = K^-1 (g0 - C K^-1 g1) + K^-1 g1 tau.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from impact.engine.layout import BRANCH_ELASTIC, D_PLASTIC, MODE_FREE, NPOLY, P_REC_DT, P_REC_T0, UNIT_SPRING

_SERIES = 0.5  # |z T| below which the integrals use their power series
# _phi0's series: below 0.05 its closed form loses more than eps / 0.05 = 4e-15 (relative) to cancellation,
# and 8 terms reach eps there (0.05^9 / 10! = 5e-19)
_PHI0_SERIES, _PHI0_TERMS = 0.05, 8
_RECIP = np.concatenate((np.zeros(1), 1.0 / np.arange(1.0, 46.0)))  # _RECIP[n] = 1 / n
# the ramp form's series (ramp_tables): below |z T| = 2 a closed form of exp(zT) - 1 - zT - (zT)^2 / 2 loses up to
# 3 digits to cancellation at 0.5 and one at 2; 45 terms reach eps of the result's size at 2 (2^44 / 45! = 1.5e-43)
_RAMP_SERIES = 2.0
#: single's columns (integral_tables, ramp_tables, flow_tables): tau^m exp(kap tau) for m < NPOLY, then
#: tau^m (exp(kap tau) - 1), then flow_change's two integrals
SINGLE_COLUMNS = 2 * NPOLY + 2
FLOW_PHI0, FLOW_PHI2 = 2 * NPOLY, 2 * NPOLY + 1


# ----------------------------------------------------------------------------
# a load record between its samples
# ----------------------------------------------------------------------------

@njit(cache=True)
def record_value(record, p, t):
    """(r0, r1, t_next): the record's value and slope at t, and its next sample time."""
    t0 = p[P_REC_T0]
    dt = p[P_REC_DT]
    n = record.shape[0]
    x = (t - t0) / dt
    i = int(math.floor(x))
    if i < 0:
        return 0.0, 0.0, t0
    if i >= n - 1:
        return 0.0, 0.0, np.inf
    t_i = t0 + i * dt
    t_next = t0 + (i + 1) * dt
    if t_next <= t:  # t sits on a sample within round-off
        i += 1
        if i >= n - 1:
            return 0.0, 0.0, np.inf
        t_i = t_next
        t_next = t0 + (i + 1) * dt
    slope = (record[i + 1] - record[i]) / dt
    if t == t_i:
        return record[i], slope, t_next
    return record[i] + slope * (t - t_i), slope, t_next


@njit(cache=True)
def whole_step(p, t, t_next, t_end):
    """The length of the record's step from t to t_next: the record's dt where the step is a whole sample step
    (not the difference of two rounded times, so that every such step shares one set of tables), else the
    difference."""
    tau = t_next - t
    if t_next < t_end and abs(tau - p[P_REC_DT]) <= 1e-9 * p[P_REC_DT]:
        return p[P_REC_DT]
    return tau


# ----------------------------------------------------------------------------
# evaluation of one coefficient-form row
# ----------------------------------------------------------------------------



@njit(cache=True)
def poly_at(p, tau):
    """A row's cubic at tau, in the one order of operations every step reads it in (the same bits everywhere)."""
    return p[0] + tau * (p[1] + tau * (p[2] + tau * p[3]))


@njit(cache=True)
def poly_slope_at(p, tau):
    """The cubic's slope at tau, likewise."""
    return p[1] + tau * (2.0 * p[2] + 3.0 * tau * p[3])


@njit(cache=True)
def eval2(kap, c, p, tau):
    """h(tau) and h'(tau)."""
    h = 0.0
    dh = 0.0
    for k in range(kap.shape[0]):
        ck = c[k]
        if ck.real != 0.0 or ck.imag != 0.0:
            kk = kap[k]
            if kk.real == 0.0 and kk.imag == 0.0:
                h += ck.real  # a constant: exp(0) = 1 exactly, no exponential to evaluate
                continue
            z = ck * np.exp(kk * tau)
            h += z.real
            dh += (z * kk).real
    # this order of sums, with p[0] and p[3] last, makes a row with p[0] = p[3] = 0 give the very bits
    # of the paper kernel's h + p1 tau + p2 tau^2: both kernels share this search and must not drift apart
    return (h + p[1] * tau + p[2] * tau * tau + p[0] + p[3] * tau * tau * tau,
            dh + p[1] + 2.0 * p[2] * tau + 3.0 * p[3] * tau * tau)


@njit(cache=True)
def eval3(kap, c, p, tau):
    """h, h' and h'' at tau."""
    h = 0.0
    dh = 0.0
    ddh = 0.0
    for k in range(kap.shape[0]):
        ck = c[k]
        if ck.real != 0.0 or ck.imag != 0.0:
            z = ck * np.exp(kap[k] * tau)
            h += z.real
            z = z * kap[k]
            dh += z.real
            ddh += (z * kap[k]).real
    h += poly_at(p, tau)
    dh += poly_slope_at(p, tau)
    ddh += 2.0 * p[2] + 6.0 * tau * p[3]
    return h, dh, ddh


@njit(cache=True)
def deriv_at0(kap, c, p, n):
    """n-th derivative at tau = 0 (exponential and polynomial parts)."""
    acc = 0.0
    for k in range(kap.shape[0]):
        z = c[k]
        for _ in range(n):
            z = z * kap[k]
        acc += z.real
    if n <= 3:
        fact = 1.0
        for i in range(2, n + 1):
            fact *= i
        acc += fact * p[n]
    return acc


@njit(cache=True)
def bound(kap, c, p, n, tau_max):
    """Bound on |n-th derivative| over [0, tau_max].

    Every homogeneous mode decays or oscillates (Re kap <= 0) and the
    harmonic slots have |exp| = 1, so |exp(kap tau)| <= 1.
    """
    acc = 0.0
    for k in range(kap.shape[0]):
        acc += abs(c[k]) * abs(kap[k]) ** n
    return acc + poly_bound(p, n, tau_max)


@njit(cache=True)
def poly_bound(p, n, tau_max):
    """Bound on |n-th derivative| of the polynomial part over [0, tau_max]."""
    if n == 0:
        return abs(p[0]) + tau_max * (abs(p[1]) + tau_max * (abs(p[2]) + tau_max * abs(p[3])))
    if n == 1:
        return abs(p[1]) + tau_max * (2.0 * abs(p[2]) + 3.0 * tau_max * abs(p[3]))
    if n == 2:
        return 2.0 * abs(p[2]) + 6.0 * tau_max * abs(p[3])
    if n == 3:
        return 6.0 * abs(p[3])
    return 0.0


@njit(cache=True)
def kappa_powers(kap, kpow):
    """kpow[n, k] = |kap_k|^n, n = 0..4, for bound_tab."""
    for k in range(kap.shape[0]):
        a = abs(kap[k])
        kpow[0, k] = 1.0
        for n in range(1, kpow.shape[0]):
            kpow[n, k] = kpow[n - 1, k] * a


@njit(cache=True)
def bound_tab(kpow, c, p, n, tau_max):
    """bound() with the powers of |kap| from a table: the scene core's hot paths call it every step."""
    acc = 0.0
    for k in range(c.shape[0]):
        ck = c[k]
        if ck.real != 0.0 or ck.imag != 0.0:
            acc += np.sqrt(ck.real * ck.real + ck.imag * ck.imag) * kpow[n, k]
    return acc + poly_bound(p, n, tau_max)


@njit(cache=True)
def derivative_row(kap, c, p, cd, pd):
    """The derivative of a row, written into (cd, pd)."""
    for k in range(kap.shape[0]):
        cd[k] = c[k] * kap[k]
    pd[0] = p[1]
    pd[1] = 2.0 * p[2]
    pd[2] = 3.0 * p[3]
    pd[3] = 0.0


@njit(cache=True)
def state_from_exp(kap, ek, C, P, tau, q, v):
    """Positions and velocities of every degree of freedom at tau, from ek = exp(kap tau)."""
    nt = kap.shape[0]
    for i in range(C.shape[0]):
        x = 0.0
        dx = 0.0
        for k in range(nt):
            ck = C[i, k]
            if ck.real != 0.0 or ck.imag != 0.0:
                z = ck * ek[k]
                x += z.real
                dx += (z * kap[k]).real
        p = P[i]
        q[i] = x + poly_at(p, tau)
        v[i] = dx + p[1] + tau * (2.0 * p[2] + 3.0 * tau * p[3])


@njit(cache=True)
def flow_change(w, s, tau, harmonic, theta0):
    """The change of the reduced state over [0, tau] of the segment build_segment set up in slot s, each mode
    advanced from the state itself: eta(tau) - eta(0) = (lam eta(0) + a) phi1 + b phi2, with a + b t the mode's
    share of the load, phi1 the integral over [0, tau] of exp(lam u) and phi2 that of exp(lam u) (tau - u), read
    from w.single (flow_tables over the same tau).

    The rows reach the same state through a particular solution of the load over the mode's eigenvalue, and its
    square for the load's slope: beside a storey yielding with a post-yield stiffness near zero these are
    kilometres in a segment that moves millimetres, and their round-off, left in the state at every segment's
    end, walked the energy balance to 1e-8 (docs/model.md, "Near zero the flow loses digits").  Here every term
    is of the size of the change it makes.  Written into w.wf: the state less a harmonic load's particular
    solution at [2n, 4n) (positions, then velocities), its change at [4n, 6n); wf[:2n] holds the load (g0, g1)
    as build_segment left it; w.wc[:2n] is scratch (each mode's change).
    """
    n = w.size[s]
    lam, vec, vinv, mred, fidx, zc, wf, wc, single, q, v = (w.lam, w.vec, w.vinv, w.mass, w.dof, w.forced, w.wf,
                                                            w.wc, w.single, w.q, w.v)
    Y0, DX = 2 * n, 4 * n  # wf: g0 | g1 | the state | its change, which first holds g0 and g1 over the masses
    for i in range(n):
        full = fidx[s, i]
        wf[Y0 + i] = q[full]
        wf[Y0 + n + i] = v[full]
    if harmonic:
        ph = np.exp(1j * theta0)
        for i in range(n):
            wf[Y0 + i] -= (zc[s, i] * ph).imag
            wf[Y0 + n + i] -= (zc[s, n + i] * ph).imag
    _load_over_mass(n, s, mred, wf, DX)
    for k in range(2 * n):
        a, b = _modal_load(n, s, k, vinv, wf, DX)
        eta = 0.0 + 0.0j
        for l in range(2 * n):
            eta += vinv[s, k, l] * wf[Y0 + l]
        wc[k] = (lam[s, k] * eta + a) * single[k, FLOW_PHI0] + b * single[k, FLOW_PHI2]
    for i in range(2 * n):
        wf[DX + i] = 0.0
    for k in range(2 * n):
        d = wc[k]
        for i in range(2 * n):
            wf[DX + i] += (vec[s, i, k] * d).real


@njit(cache=True)
def take_flow_state(w, s, tau, harmonic, theta0, omega, units, nf):
    """The state at tau from flow_change: the reduced degrees of freedom, the units their floor holds (its state and
    their offset, as their rows are the floor's), the free units without a spring from their polynomial rows, and
    identical spring units given one row (_copy_identical_rows) the same state, bit for bit."""
    n = w.size[s]
    fidx, zc, wf, q, v, mode, offset, C, P = w.dof, w.forced, w.wf, w.q, w.v, w.mode, w.offset, w.C, w.P
    Y0, DX = 2 * n, 4 * n
    for i in range(n):
        full = fidx[s, i]
        q[full] = wf[Y0 + i] + wf[DX + i]
        v[full] = wf[Y0 + n + i] + wf[DX + n + i]
    if harmonic:
        ph = np.exp(1j * (theta0 + omega * tau))
        for i in range(n):
            full = fidx[s, i]
            q[full] += (zc[s, i] * ph).imag
            v[full] += (zc[s, n + i] * ph).imag
    ufloor = units.floor
    for j in range(mode.shape[0]):
        if mode[j] != MODE_FREE:
            q[nf + j] = q[ufloor[j]] + offset[j]
            v[nf + j] = v[ufloor[j]]
        elif not units.kind[j] & UNIT_SPRING:
            p = P[nf + j]  # a free unit without a spring moves on its polynomial alone (build_segment)
            q[nf + j] = poly_at(p, tau)
            v[nf + j] = poly_slope_at(p, tau)
        elif j > 0 and mode[j - 1] == MODE_FREE and _same_row(C, P, nf + j - 1, nf + j):
            q[nf + j] = q[nf + j - 1]
            v[nf + j] = v[nf + j - 1]


@njit(cache=True)
def _same_row(C, P, a, b):
    """Whether rows a and b are one row, bit for bit."""
    for k in range(C.shape[1]):
        if C[a, k] != C[b, k]:
            return False
    for k in range(P.shape[1]):
        if P[a, k] != P[b, k]:
            return False
    return True


# ----------------------------------------------------------------------------
# configurations: assembly and eigen-data, cached
# ----------------------------------------------------------------------------

@njit(cache=True)
def config_key(mode):
    key = 0
    for j in range(mode.shape[0]):
        if mode[j] != MODE_FREE:
            key |= 1 << j
    return key


@njit(cache=True)
def scene_key(mode, yld):
    """The configuration's key: the units held by their floor (config_key) and, after them, the storeys on a
    yielding branch (whose stiffness is b k); up or down does not change the stiffness, only the constant force."""
    key = config_key(mode)
    if yld is not None:
        nu = mode.shape[0]
        branch = yld.branch
        for i in range(branch.shape[0]):
            if branch[i] != BRANCH_ELASTIC:
                key |= 1 << (nu + i)
    return key


@njit(cache=True)
def storey_stiffness(yld, kr):
    """P-delta's geometric stiffness -P/h on every storey, and a yielding storey's stiffness taken down to b k;
    returns how many storeys are left without stiffness (yielding, b = 0, no P-delta): K's zero modes."""
    flat = 0
    for i in range(yld.stiffness.shape[0]):
        dk = -yld.geometric[i]
        if yld.branch[i] != BRANCH_ELASTIC:
            dk -= (1.0 - yld.hardening[i]) * yld.stiffness[i]
            if yld.hardening[i] == 0.0 and yld.geometric[i] == 0.0:
                flat += 1
        if dk != 0.0:
            kr[i, i] += dk
            if i > 0:
                kr[i - 1, i - 1] += dk
                kr[i - 1, i] -= dk
                kr[i, i - 1] -= dk
    return flat


@njit(cache=True)
def _snap_rigid_modes(lam, n, count):
    """The `count` eigenvalues nearest zero made exactly zero: each perfectly plastic storey on its yielding branch
    (b = 0, no P-delta) leaves the floors above it free to drift, a mode of K with zero frequency, whose eigenvalue
    the solver returns as round-off of the largest times the basis' condition.  K's rank falls by one per such
    storey (a shear building's stiffness is a sum of independent storey terms), so the count is known, not guessed
    from a threshold.  Its particular solution is a polynomial (build_segment), its exponential a constant
    (segment.eval2 reads a zero exponent as 1)."""
    order = np.argsort(np.abs(lam[:2 * n]))
    for k in range(count):
        lam[order[k]] = 0.0


#: the largest correction of a mode's shape (its largest entry 1) that a Newton step may make.  Beside two zero modes
#: the eigensolver's shape of the slow damped mode can be off by 1e-3 (probe scene 1796249627-1540: one step of
#: 1.0e-3 takes its residual from 2.4e-3 to 3e-11), so the bound is well above that; what keeps a step inside its
#: own eigenpair's basin is the eigenvalue's bound beside it (_REFINE_NEIGHBOUR)
_REFINE_REACH = 1e-2
_REFINE_NEIGHBOUR = 0.1  # the largest move of an eigenvalue, as a fraction of its distance to the nearest other
#: eigenvalues closer than this, relative to their size, are twins (identical units): the Newton step on either of
#: a twin pair is singular, so the pair keeps the eigensolver's shapes
_TWIN = 1e-6


@njit(cache=True)
def _nearest_other(lam, k, n):
    """The distance from lam[k] to the nearest other eigenvalue."""
    nearest = np.inf
    for j in range(2 * n):
        if j != k:
            nearest = min(nearest, abs(lam[j] - lam[k]))
    return nearest


@njit(cache=True)
def _rigid_bodies(yld, dof, ufloor, nf, n, flat):
    """K's null space, exactly: one column per storey without stiffness, 1 on every floor above it (and on the units
    hung on those floors), 0 below: the floors above a perfectly plastic storey drift as one."""
    out = np.zeros((n, flat))
    c = 0
    for i in range(yld.stiffness.shape[0]):
        if yld.branch[i] != BRANCH_ELASTIC and yld.hardening[i] == 0.0 and yld.geometric[i] == 0.0:
            for r in range(n):
                floor = dof[r] if dof[r] < nf else ufloor[dof[r] - nf]
                if floor >= i:
                    out[r, c] = 1.0
            c += 1
    return out


@njit(cache=True)
def _refine_modes(lam, vec, m, kr, cr, n, rigid):
    """Each eigenpair of a configuration with zero modes made consistent to the round-off of its own residual.

    Beside a perfectly plastic storey's zero mode sits a slow damped one (the floors above it coasting to their
    terminal velocity under the yield force), whose amplitude and the particular solution's are metres where the
    motion is millimetres: the eigensolver's error in its shape (1e-5 there, the zero modes beside it) times those
    metres was newtons of force left over (probe scene 3297466453-1137: 6 N of 5e6, an energy balance off by
    3e-7).  Newton steps on (lam^2 M + lam C + K) psi = 0, whose residual is evaluated to eps |K| |psi|, bring
    every mode's shape psi to that; a zero mode is K's null space exactly (rigid), its velocity part zero."""
    zero = 0
    for k in range(2 * n):
        if lam[k] == 0.0:
            psi = rigid[:, zero].astype(np.complex128)
            zero += 1
        else:
            psi = vec[:n, k] / vec[np.argmax(np.abs(vec[:n, k])), k]
            nearest = _nearest_other(lam, k, n)
            if nearest > _TWIN * abs(lam[k]):
                lam[k] = _newton_refined(lam[k], psi, m, kr, cr, n, _REFINE_NEIGHBOUR * nearest)
        for i in range(n):
            vec[i, k] = psi[i]
            vec[n + i, k] = lam[k] * psi[i]


@njit(cache=True)
def _newton_refined(lk, psi, m, kr, cr, n, lam_reach):
    """Two Newton steps on the quadratic eigenproblem from (lk, psi), psi's largest entry held at 1 (psi refined in
    place, the eigenvalue returned); a step that would move the shape beyond _REFINE_REACH or the eigenvalue beyond
    lam_reach could leave the pair's basin and is not taken."""
    pivot = np.argmax(np.abs(psi))
    big = np.zeros((n + 1, n + 1), dtype=np.complex128)
    rhs = np.zeros(n + 1, dtype=np.complex128)
    big[n, pivot] = 1.0
    for _ in range(2):
        for i in range(n):
            residual = 0.0 + 0.0j
            slope = 2.0 * lk * m[i] * psi[i]  # d/dlam of row i of (lam^2 M + lam C + K) psi
            for j in range(n):
                big[i, j] = kr[i, j] + lk * cr[i, j] + (lk * lk * m[i] if i == j else 0.0)
                residual += big[i, j] * psi[j]
                slope += cr[i, j] * psi[j]
            big[i, n] = slope
            rhs[i] = -residual
        step = np.linalg.solve(big, rhs)
        if not np.all(np.isfinite(step)) or np.max(np.abs(step[:n])) > _REFINE_REACH or abs(step[n]) > lam_reach:
            break
        for i in range(n):
            psi[i] += step[i]
        lk += step[n]
    return lk


@njit(cache=True)
def join(matrix, a, b, value):
    """A spring (or dashpot) of stiffness value between degrees of freedom a and b, added into matrix."""
    matrix[a, a] += value
    matrix[b, b] += value
    matrix[a, b] -= value
    matrix[b, a] -= value


@njit(cache=True)
def _assemble(building, units, springs, yld, load_vec, mode, cache, s):
    """Reduced M, K, C and the reduced load of one configuration, into slot s.

    A yielding building (yld) changes K by its storeys' branches and P-delta; where that leaves K singular (a
    perfectly plastic storey yielding), K^-1 is not formed and build_segment takes the particular solution through
    the modes."""
    mb, kb, cb = building
    ukind, ufloor, um = units.kind, units.floor, units.mass
    keys, nr, lam, vec, vinv, kinv, cred, fidx, ellr, zc, mred = cache
    nf = mb.shape[0]
    nu = um.shape[0]
    fidx[s, :] = -1
    n = nf
    for i in range(nf):
        fidx[s, i] = i
    if springs is not None:
        for j in range(nu):
            if ukind[j] & UNIT_SPRING and mode[j] == MODE_FREE:
                fidx[s, n] = nf + j
                n += 1
    m = np.zeros(n)
    kr = np.zeros((n, n))
    cr = np.zeros((n, n))
    lr = np.zeros(n)
    for a in range(nf):
        m[a] = mb[a]
        lr[a] = load_vec[a]
        for b in range(nf):
            kr[a, b] = kb[a, b]
            cr[a, b] = cb[a, b]
    for j in range(nu):
        if mode[j] != MODE_FREE:
            f = ufloor[j]
            m[f] += um[j]
            lr[f] += load_vec[nf + j]
    if springs is not None:
        uk, uc = springs
        for r in range(nf, n):
            j = fidx[s, r] - nf
            m[r] = um[j]
            lr[r] = load_vec[nf + j]
            join(kr, ufloor[j], r, uk[j])
            join(cr, ufloor[j], r, uc[j])
    flat = 0
    if yld is not None:
        flat = storey_stiffness(yld, kr)
    a_mat = np.zeros((2 * n, 2 * n), dtype=np.complex128)
    for i in range(n):
        a_mat[i, n + i] = 1.0
        for j in range(n):
            a_mat[n + i, j] = -kr[i, j] / m[i]
            a_mat[n + i, n + j] = -cr[i, j] / m[i]
    w, v = np.linalg.eig(a_mat)
    if flat == 0:
        ki = np.linalg.inv(kr)
    else:
        ki = np.zeros((n, n))
        _snap_rigid_modes(w, n, flat)
        _refine_modes(w, v, m, kr, cr, n, _rigid_bodies(yld, fidx[s], ufloor, nf, n, flat))
    vi = np.linalg.inv(v)
    nr[s] = n
    lam[s, :] = 0.0
    vec[s, :, :] = 0.0
    vinv[s, :, :] = 0.0
    kinv[s, :, :] = 0.0
    cred[s, :, :] = 0.0
    ellr[s, :] = 0.0
    for i in range(2 * n):
        lam[s, i] = w[i]
        for j in range(2 * n):
            vec[s, i, j] = v[i, j]
            vinv[s, i, j] = vi[i, j]
    mred[s, :] = 0.0
    for i in range(n):
        ellr[s, i] = lr[i]
        mred[s, i] = m[i]
        for j in range(n):
            kinv[s, i, j] = ki[i, j]
            cred[s, i, j] = cr[i, j]
    return a_mat, m, lr, n


@njit(cache=True)
def config_slot(building, units, springs, yld, load_vec, omega, mode, cache, cursor):
    """The cache slot holding this configuration's eigen-data (assembled on a miss).

    omega > 0: the load is harmonic at that frequency and the slot also holds
    the complex amplitude zc of the particular solution per unit load.
    cursor: one-element array, the slot to replace next.
    """
    keys = cache.key
    key = scene_key(mode, yld)
    for s in range(keys.shape[0]):
        if keys[s] == key:
            return s
    s = cursor[0]
    cursor[0] = (s + 1) % keys.shape[0]
    a_mat, m, lr, n = _assemble(building, units, springs, yld, load_vec, mode, cache, s)
    zc = cache.forced
    zc[s, :] = 0.0
    if omega > 0.0:
        # particular solution mode by mode: a mode the load does not reach (the opposite swing of
        # identical undamped pendulums, say) has no part in it even when it sits at the load's frequency
        vec, vinv = cache.vec, cache.vinv
        rhs = np.zeros(2 * n, dtype=np.complex128)
        for i in range(n):
            rhs[n + i] = lr[i] / m[i]
        modal = np.zeros(2 * n, dtype=np.complex128)
        size = 0.0
        for k in range(2 * n):
            for i in range(2 * n):
                modal[k] += vinv[s, k, i] * rhs[i]
            size = max(size, abs(modal[k]))
        for k in range(2 * n):
            if abs(modal[k]) <= 1e-13 * size:
                modal[k] = 0.0
            else:
                gap = 1j * omega - cache.lam[s, k]
                if abs(gap) <= 1e-12 * abs(cache.lam[s, k]):
                    raise ValueError("the harmonic load drives an undamped mode at its natural frequency: "
                                     "the forced response is unbounded (add damping or change the frequency)")
                modal[k] = modal[k] / gap
        for i in range(2 * n):
            acc = 0.0 + 0.0j
            for k in range(2 * n):
                acc += vec[s, i, k] * modal[k]
            zc[s, i] = acc
    keys[s] = key
    return s


# ----------------------------------------------------------------------------
# a segment
# ----------------------------------------------------------------------------

@njit(cache=True)
def build_segment(w, s, units, springs, fric, yld, harmonic, load_at, omega):
    """Coefficient rows w.C, w.P (over exponents w.kap) of every degree of freedom from the state (w.q, w.v) in
    configuration slot s of w.cache; w: bundles.SegmentWork.

    load_at = (theta0, r0, r1): r0 + r1 tau is the record's value on the segment (per unit of load_vec);
    harmonic: the load is sin(theta0 + omega tau) per unit of load_vec.
    w.wf, w.wc (floats, complexes): scratch of 7 and 4 times the largest reduced size, so that a
    segment allocates nothing; the modal amplitudes are left in complexes[2n:4n] (the modal shortcuts read them).
    yld: a yielding building's storeys (bundles.YieldArrays), whose constant forces join the load; where a perfectly
    plastic storey leaves K singular (a zero mode), the particular solution is taken through the modes
    (_modal_particular), and through K^-1 as for an elastic building everywhere else, which a stiff pendulum's
    ill-conditioned eigenbasis does not reach.
    """
    mode, offset, sigma, q, v, kap, C, P = w.mode, w.offset, w.sigma, w.q, w.v, w.kap, w.C, w.P
    theta0, r0, r1 = load_at
    nf = C.shape[0] - units.mass.shape[0]
    nr, lam, vec, vinv, kinv, cred, fidx, ellr, zc = w.size, w.lam, w.vec, w.vinv, w.kinv, w.damping, w.dof, w.load, w.forced
    ufloor, um, uload = units.floor, units.mass, units.load
    n = nr[s]
    nt = kap.shape[0]
    for k in range(nt):
        kap[k] = 0.0
    for k in range(2 * n):
        kap[k] = lam[s, k]
    if harmonic:
        kap[nt - 2] = 1j * omega
        kap[nt - 1] = -1j * omega
    # scratch by offset, not by slices: a slice is a new array object on every segment
    # (wf: g0 | g1 | u1 | qp | tmp | dz, the state minus the particular solution; wc[2n:4n]: amplitudes)
    wf, wc = w.wf, w.wc
    G0, G1, U1, QP, TMP, DZ = 0, n, 2 * n, 3 * n, 4 * n, 5 * n
    for i in range(n):
        wf[G0 + i] = ellr[s, i] * r0
        wf[G1 + i] = ellr[s, i] * r1
    if fric is not None:
        for j in range(um.shape[0]):
            if mode[j] == MODE_FREE and fric[j] > 0.0:
                # a sliding mass drags its floor along with m a_f sigma
                wf[G0 + ufloor[j]] += um[j] * fric[j] * sigma[j]
    rigid = False
    if yld is not None:
        _storey_constants(yld, q, wf, G0)
        rigid = has_rigid_mode(w.cache, s)
    if not rigid:
        for i in range(n):
            wf[U1 + i] = 0.0
            wf[QP + i] = 0.0
            wf[TMP + i] = wf[G0 + i]
        for i in range(n):
            for j in range(n):
                wf[U1 + i] += kinv[s, i, j] * wf[G1 + j]
        for i in range(n):
            for j in range(n):
                wf[TMP + i] -= cred[s, i, j] * wf[U1 + j]
        for i in range(n):
            for j in range(n):
                wf[QP + i] += kinv[s, i, j] * wf[TMP + j]
    else:
        _modal_particular(n, s, lam, vec, vinv, w.mass, wf)
    ph = np.exp(1j * theta0)
    for i in range(n):
        full = fidx[s, i]
        wf[DZ + i] = q[full] - wf[QP + i]
        wf[DZ + n + i] = v[full] - wf[U1 + i]
        if harmonic:
            wf[DZ + i] -= (zc[s, i] * ph).imag
            wf[DZ + n + i] -= (zc[s, n + i] * ph).imag
    W = 2 * n  # the modal amplitudes, once for every row
    for k in range(2 * n):
        wk = 0.0 + 0.0j
        for l in range(2 * n):
            wk += vinv[s, k, l] * wf[DZ + l]
        wc[W + k] = wk
    for i in range(n):
        full = fidx[s, i]
        # the row starts exactly at its state: the polynomial, the particular solution's position and velocity,
        # is taken as what the modes leave of q and v at tau = 0.  Equal in exact arithmetic; but through an
        # ill-conditioned basis (a pendulum hundreds of times stiffer than its building, identical units) the
        # modes meet the state only to round-off times the basis' condition, and a unit set on its wall would
        # start read off it (docs/model.md, "Contact decisions above round-off")
        h0 = 0.0
        h1 = 0.0
        for k in range(2 * n):
            c = vec[s, i, k] * wc[W + k]
            C[full, k] = c
            h0 += c.real
            h1 += c.real * kap[k].real - c.imag * kap[k].imag
        for k in range(2 * n, nt):
            C[full, k] = 0.0
        if harmonic:
            ch = zc[s, i] * ph / 2j
            C[full, nt - 2] = ch
            C[full, nt - 1] = ch.conjugate()
            h0 += 2.0 * ch.real
            h1 -= 2.0 * omega * ch.imag
        P[full, 0] = q[full] - h0
        P[full, 1] = v[full] - h1
        P[full, 2] = wf[TMP + i] if rigid else 0.0  # a zero mode's particular solution is quadratic
        P[full, 3] = 0.0
    _copy_identical_rows(units, springs, mode, nf, q, v, C, P)
    for j in range(um.shape[0]):
        row = nf + j
        if mode[j] != MODE_FREE:
            f = ufloor[j]
            for k in range(nt):
                C[row, k] = C[f, k]
            for k in range(NPOLY):
                P[row, k] = P[f, k]
            P[row, 0] += offset[j]
        elif not units.kind[j] & UNIT_SPRING:
            for k in range(nt):
                C[row, k] = 0.0
            a0 = uload[j] * r0
            a1 = uload[j] * r1
            if fric is not None:
                a0 -= fric[j] * sigma[j]
            P[row, 0] = q[row]
            P[row, 1] = v[row]
            P[row, 2] = 0.5 * a0
            P[row, 3] = a1 / 6.0


@njit(cache=True)
def _storey_constants(yld, q, wf, g0):
    """Each storey's constant force onto the reduced load at wf[g0:]: its restoring force is k u - (1 - b) k p on
    the elastic branch and b k u + s (1 - b) k d_y on a yielding one (s = +-1), whose k u and b k u are in K."""
    branch, k, b, dy, p = yld.branch, yld.stiffness, yld.hardening, yld.yield_drift, yld.offset
    for i in range(k.shape[0]):
        if branch[i] == BRANCH_ELASTIC:
            r0 = -(1.0 - b[i]) * k[i] * p[i]
        else:
            r0 = branch[i] * (1.0 - b[i]) * k[i] * dy[i]
        wf[g0 + i] -= r0
        if i > 0:
            wf[g0 + i - 1] += r0


@njit(cache=True)
def _load_over_mass(n, s, mred, wf, at):
    """The reduced load g0, g1 that build_segment left in wf[:n], wf[n:2n], each over its mass, into wf[at:at + 2n]
    (one division per degree of freedom, not one per mode)."""
    for r in range(n):
        wf[at + r] = wf[r] / mred[s, r]
        wf[at + n + r] = wf[n + r] / mred[s, r]


@njit(cache=True)
def _modal_load(n, s, k, vinv, wf, at):
    """Mode k's share (a, b) of the load g0 + g1 tau, given over the masses at wf[at:at + 2n] (_load_over_mass)."""
    a = 0.0 + 0.0j
    b = 0.0 + 0.0j
    for r in range(n):
        a += vinv[s, k, n + r] * wf[at + r]
        b += vinv[s, k, n + r] * wf[at + n + r]
    return a, b


@njit(cache=True)
def _modal_particular(n, s, lam, vec, vinv, mred, wf):
    """The particular solution of M q'' + C q' + K q = g0 + g1 tau through the modes, for any K (a singular one too).

    Mode k's amplitude obeys eta' = lam eta + a + b tau (a, b: the load's modal parts); its polynomial solution is
    -(a + b / lam) / lam - b tau / lam, or a tau + b tau^2 / 2 for a zero mode.  Written into
    wf: the positions at tau = 0 (QP, 3n), the velocities at 0 (U1, 2n) and the tau^2 coefficients (TMP, 4n).
    """
    U1, QP, TMP, SCALED = 2 * n, 3 * n, 4 * n, 5 * n  # after g0, g1; SCALED: scratch of 2n
    for i in range(n):
        wf[U1 + i] = 0.0
        wf[QP + i] = 0.0
        wf[TMP + i] = 0.0
    _load_over_mass(n, s, mred, wf, SCALED)
    for k in range(2 * n):
        a, b = _modal_load(n, s, k, vinv, wf, SCALED)
        lk = lam[s, k]
        gamma = 0.0 + 0.0j
        if lk == 0.0:
            alpha = 0.0 + 0.0j
            gamma = 0.5 * b
        else:
            alpha = -(a + b / lk) / lk
        for i in range(n):
            wf[QP + i] += (vec[s, i, k] * alpha).real
            wf[U1 + i] += (vec[s, n + i, k] * alpha).real
            wf[TMP + i] += (vec[s, i, k] * gamma).real


@njit(cache=True)
def same_unit(units, springs, i, j):
    """Whether units i and j are identical: kind, floor, mass, load, gap, restitution, spring and dashpot."""
    kind, floor, mass, load, gap, rest = units
    if kind[i] != kind[j] or floor[i] != floor[j] or mass[i] != mass[j] or load[i] != load[j] \
            or gap[i] != gap[j] or rest[i] != rest[j]:
        return False
    if springs is not None:
        if springs.stiffness[i] != springs.stiffness[j] or springs.damping[i] != springs.damping[j]:
            return False
    return True


@njit(cache=True)
def _copy_identical_rows(units, springs, mode, nf, q, v, C, P):
    """Identical spring units in identical states move identically: give them the same row, bit for bit.

    The eigen-basis of a system with identical units is degenerate and
    arbitrary, so their rows computed one by one differ by round-off, which
    would split a multi-unit damper's simultaneous impacts into a cascade.
    By the permutation symmetry the exact rows are equal; copying keeps them so.
    """
    kind = units.kind
    for j in range(1, kind.shape[0]):
        i = j - 1
        if not kind[j] & UNIT_SPRING or mode[j] != MODE_FREE or mode[i] != MODE_FREE:
            continue
        if not same_unit(units, springs, i, j):
            continue
        if q[nf + i] != q[nf + j] or v[nf + i] != v[nf + j]:
            continue
        for k in range(C.shape[1]):
            C[nf + j, k] = C[nf + i, k]
        for k in range(NPOLY):
            P[nf + j, k] = P[nf + i, k]


# ----------------------------------------------------------------------------
# exact integrals over [0, T]
# ----------------------------------------------------------------------------

@njit(cache=True)
def _phi0(z, big_t, ez):
    """Integral over [0, T] of exp(z tau); ez = exp(z T).

    Below |z T| = _PHI0_SERIES by its power series: (ez - 1) / z loses eps / |z T| to cancellation, 1e-13 at
    |z T| = 1e-3, and a lightly damped pair (z = 2 Re kap) sits there on every short segment.
    """
    zt = z * big_t
    if zt.real * zt.real + zt.imag * zt.imag < _PHI0_SERIES * _PHI0_SERIES:
        # sum_n (zT)^n / (n + 1)! by Horner, to the term below eps at |zT| = _PHI0_SERIES
        acc = 1.0 + 0.0j
        for n in range(_PHI0_TERMS, 0, -1):
            acc = 1.0 + zt * acc * _RECIP[n + 1]
        return acc * big_t
    return (ez - 1.0) / z


#: terms of _phi2's series: at |z T| = _RAMP_SERIES the 25th is 2^25 / 27! = 3e-21 of the first
_PHI2_TERMS = 25


@njit(cache=True)
def _phi2(z, big_t, ez):
    """Integral over [0, T] of exp(z u) (T - u) du, (ez - 1 - z T) / z^2; ez = exp(z T).

    Below |z T| = _RAMP_SERIES by its power series, T^2 sum_n (zT)^n / (n + 2)!, by Horner: the closed form loses
    eps / |z T|^2 to cancellation, and a slow mode sits at |z T| of 1e-3 on a record's sample step.
    """
    zt = z * big_t
    if zt.real * zt.real + zt.imag * zt.imag < _RAMP_SERIES * _RAMP_SERIES:
        acc = 1.0 + 0.0j
        for n in range(_PHI2_TERMS, 0, -1):
            acc = 1.0 + zt * acc * _RECIP[n + 2]
        return 0.5 * acc * big_t * big_t
    return (ez - 1.0 - zt) / (z * z)


@njit(cache=True)
def flow_tables(kap, ek, big_t, single):
    """flow_change's integrals over [0, T] per exponent, into single[:, FLOW_PHI0] and single[:, FLOW_PHI2]: kept
    with a record's sample step per configuration (scene_loop.step_tables), as the other tables are."""
    for k in range(kap.shape[0]):
        single[k, FLOW_PHI0] = _phi0(kap[k], big_t, ek[k])
        single[k, FLOW_PHI2] = _phi2(kap[k], big_t, ek[k])


@njit(cache=True)
def _phi_m(z, big_t, ez, single, k):
    """single[k, m] = integral over [0, T] of tau^m exp(z tau), m = 0..3."""
    zt = z * big_t
    if zt.real * zt.real + zt.imag * zt.imag < _SERIES * _SERIES:
        # sum_n (zT)^n / n! T^(m+1) / (n + m + 1): every m in one pass (reciprocals from a table: a
        # segment after every event builds these tables, and divisions dominated it)
        term = 1.0 + 0.0j
        a0 = 0.0 + 0.0j
        a1 = 0.0 + 0.0j
        a2 = 0.0 + 0.0j
        a3 = 0.0 + 0.0j
        for n in range(40):
            a0 += term * _RECIP[n + 1]
            a1 += term * _RECIP[n + 2]
            a2 += term * _RECIP[n + 3]
            a3 += term * _RECIP[n + 4]
            term = term * zt * _RECIP[n + 1]
            if term.real * term.real + term.imag * term.imag < 1e-36:
                break
        single[k, 0] = a0 * big_t
        single[k, 1] = a1 * big_t ** 2
        single[k, 2] = a2 * big_t ** 3
        single[k, 3] = a3 * big_t ** 4
        return
    val = (ez - 1.0) / z
    single[k, 0] = val
    for i in range(1, NPOLY):
        val = (big_t ** i * ez - i * val) / z
        single[k, i] = val


@njit(cache=True)
def integral_tables(kap, ek, big_t, pair, single):
    """Tables for int_prod over [0, T]: pair[k, l] of exp((kap_k + kap_l) tau), single[k, m] of tau^m exp(kap_k tau)."""
    nt = kap.shape[0]
    for k in range(nt):
        for l in range(k, nt):
            v = _phi0(kap[k] + kap[l], big_t, ek[k] * ek[l])
            pair[k, l] = v
            pair[l, k] = v
        _phi_m(kap[k], big_t, ek[k], single, k)


@njit(cache=True)
def _rest2(x, ex):
    """The integral over [0, 1] of exp(x u) - 1 - x u, du: sum over m >= 2 of x^m / (m + 1)!; ex = exp(x)."""
    if x.real * x.real + x.imag * x.imag >= _RAMP_SERIES * _RAMP_SERIES:
        return (ex - 1.0 - x - 0.5 * x * x) / x
    term = x * x * _RECIP[2] * _RECIP[3]
    acc = 0.0 + 0.0j
    for m in range(2, 44):
        acc += term
        term = term * x * _RECIP[m + 2]
        if term.real * term.real + term.imag * term.imag <= 1e-36 * (acc.real * acc.real + acc.imag * acc.imag):
            break
    return acc


@njit(cache=True)
def _ramp_series(z, big_t, single, k):
    """single[k, NPOLY + m] = integral over [0, T] of tau^m (exp(z tau) - 1), m = 0..3, by its power series
    (|z T| < _RAMP_SERIES): sum over n >= 1 of (zT)^n / n! T^(m+1) / (n + m + 1), every m in one pass."""
    zt = z * big_t
    term = zt
    a0 = 0.0 + 0.0j
    a1 = 0.0 + 0.0j
    a2 = 0.0 + 0.0j
    a3 = 0.0 + 0.0j
    for n in range(1, 41):
        a0 += term * _RECIP[n + 1]
        a1 += term * _RECIP[n + 2]
        a2 += term * _RECIP[n + 3]
        a3 += term * _RECIP[n + 4]
        term = term * zt * _RECIP[n + 1]
        if term.real * term.real + term.imag * term.imag <= 1e-36 * (a0.real * a0.real + a0.imag * a0.imag):
            break
    single[k, NPOLY] = a0 * big_t
    single[k, NPOLY + 1] = a1 * big_t ** 2
    single[k, NPOLY + 2] = a2 * big_t ** 3
    single[k, NPOLY + 3] = a3 * big_t ** 4


@njit(cache=True)
def ramp_tables(kap, ek, big_t, ramp, single):
    """The ramp form's tables over [0, T]: ramp[k, l] of (exp(kap_k tau) - 1)(exp(kap_l tau) - 1), and
    single[k, NPOLY + m] of tau^m (exp(kap_k tau) - 1), each to round-off of its own size; single[k, :NPOLY] must
    hold integral_tables' over the same T, whose closed form the ramp's takes where it keeps its digits.

    Under a record a slow mode's row is an exponential and a polynomial of the load over the mode's frequency
    squared, far larger than the motion they cancel to, and a product of two such rows integrated term by term
    (int_prod) keeps the square of that cancellation.  Written from its start value, a velocity row is
    v0 + sum_k c_k (exp(kap_k tau) - 1) (+ a polynomial without constant), whose terms are the size of the
    motion's change: int_prod_ramp integrates those.  (exp(a t) - 1)(exp(b t) - 1) is
    r(a + b) - r(a) - r(b) with r(z) = exp(z t) - 1 - z t, whose first orders cancel exactly."""
    nt = kap.shape[0]
    for k in range(nt):
        zt = kap[k] * big_t
        ramp[k, k] = _rest2(zt, ek[k])  # r(kap_k T), held on the diagonal until its row is made (no allocation)
        if zt.real * zt.real + zt.imag * zt.imag >= _RAMP_SERIES * _RAMP_SERIES:
            for m in range(NPOLY):
                single[k, NPOLY + m] = single[k, m] - big_t ** (m + 1) * _RECIP[m + 1]
        else:
            _ramp_series(kap[k], big_t, single, k)
    for k in range(nt):
        rest_k = ramp[k, k]
        for l in range(k + 1, nt):  # the diagonal's r(kap_l T) of the later rows are still there to read
            v = big_t * (_rest2((kap[k] + kap[l]) * big_t, ek[k] * ek[l]) - rest_k - ramp[l, l])
            ramp[k, l] = v
            ramp[l, k] = v
        ramp[k, k] = big_t * (_rest2((kap[k] + kap[k]) * big_t, ek[k] * ek[k]) - rest_k - rest_k)


@njit(cache=True)
def int_prod_ramp(big_t, ramp, single, a0, ca, pa, b0, cb, pb):
    """Integral over [0, T] of the product of two rows, each written from its start value (a0, b0) in the ramp
    form: a0 + sum_k ca_k (exp(kap_k tau) - 1) + pa_1 tau + pa_2 tau^2 + pa_3 tau^3 (ramp_tables)."""
    if big_t <= 0.0:
        return 0.0
    nt = ca.shape[0]
    acc = 0.0 + 0.0j
    for j in range(nt):
        inner = b0 * single[j, NPOLY]
        cross = a0 * single[j, NPOLY]
        for m in range(1, NPOLY):
            inner += pb[m] * single[j, NPOLY + m]
            cross += pa[m] * single[j, NPOLY + m]
        for l in range(nt):
            inner += cb[l] * ramp[j, l]
        acc += ca[j] * inner + cb[j] * cross
    poly = a0 * b0 * big_t
    for m in range(1, NPOLY):
        tp = big_t ** (m + 1) * _RECIP[m + 1]
        poly += (a0 * pb[m] + b0 * pa[m]) * tp
    for i in range(1, NPOLY):
        for j in range(1, NPOLY):
            poly += pa[i] * pb[j] * big_t ** (i + j + 1) * _RECIP[i + j + 1]
    return acc.real + poly


@njit(cache=True)
def int_prod(big_t, pair, single, ca, pa, cb, pb):
    """Integral over [0, T] of the product of two rows, from the tables of integral_tables."""
    if big_t <= 0.0:
        return 0.0
    nt = ca.shape[0]
    acc = 0.0 + 0.0j
    # plain multiply-adds, no tests for zero coefficients: the branches cost more than they save
    for j in range(nt):
        inner = 0.0 + 0.0j
        for l in range(nt):
            inner += cb[l] * pair[j, l]
        cross = 0.0 + 0.0j
        for m in range(NPOLY):
            inner += pb[m] * single[j, m]
            cross += pa[m] * single[j, m]
        acc += ca[j] * inner + cb[j] * cross
    return acc.real + poly_integral(pa, pb, big_t)


@njit(cache=True)
def poly_integral(pa, pb, big_t):
    """Integral over [0, T] of the product of two cubic polynomials."""
    out = 0.0
    for i in range(NPOLY):
        if pa[i] == 0.0:
            continue
        for j in range(NPOLY):
            if pb[j] != 0.0:
                tp = big_t
                for _ in range(i + j):
                    tp *= big_t
                out += pa[i] * pb[j] * tp / (i + j + 1)
    return out

@njit(cache=True)
def energy(building, units, springs, yld, nf, q, v):
    """Kinetic plus stored energy of the scene (relative coordinates)."""
    mb, kb, _ = building
    ufloor, um = units.floor, units.mass
    e = 0.0
    for a in range(nf):
        e += 0.5 * mb[a] * v[a] * v[a]
        if yld is None:
            for b in range(nf):
                e += 0.5 * q[a] * kb[a, b] * q[b]
    if yld is not None:
        e += storey_energy(yld, q)
    for j in range(um.shape[0]):
        e += 0.5 * um[j] * v[nf + j] * v[nf + j]
    if springs is not None:
        uk = springs.stiffness
        for j in range(um.shape[0]):
            if uk[j] != 0.0:
                s = q[nf + j] - q[ufloor[j]]
                e += 0.5 * uk[j] * s * s
    return e


@njit(cache=True)
def storey_drift(x, i):
    """Storey i's drift (or drift velocity, from velocities): its floor less the one below (the ground for i = 0)."""
    return x[i] - x[i - 1] if i > 0 else x[0]


@njit(cache=True)
def storey_energy(yld, q):
    """What a yielding building's storeys store: b k u^2 / 2 in the hardening spring, (1 - b) k (u - p)^2 / 2 in the
    perfectly plastic element and -P u^2 / (2 h) of gravity through P-delta; on a yielding branch u - p is s d_y."""
    k, b, dy, g, branch, p = yld.stiffness, yld.hardening, yld.yield_drift, yld.geometric, yld.branch, yld.offset
    e = 0.0
    for i in range(k.shape[0]):
        u = storey_drift(q, i)
        el = u - p[i] if branch[i] == BRANCH_ELASTIC else branch[i] * dy[i]
        e += 0.5 * b[i] * k[i] * u * u + 0.5 * (1.0 - b[i]) * k[i] * el * el - 0.5 * g[i] * u * u
    return e


@njit(cache=True)
def has_rigid_mode(cache, s):
    """Whether slot s has a zero mode (_snap_rigid_modes), whose particular solution is quadratic."""
    for k in range(2 * cache.size[s]):
        if cache.lam[s, k] == 0.0:
            return True
    return False


@njit(cache=True)
def storey_gravity(yld, q):
    """P u^2 / h summed over the storeys: twice the size of P-delta's energy, -P u^2 / (2h), which storey_energy
    subtracts (what the energy balance's scale adds back, so that the scale counts it by its size)."""
    g = yld.geometric
    e = 0.0
    for i in range(g.shape[0]):
        u = storey_drift(q, i)
        e += g[i] * u * u
    return e


@njit(cache=True)
def plastic_flow(yld, q, diag):
    """A yielding storey's offset follows its drift (u - p = s d_y), and the perfectly plastic element's force
    s (1 - b) k d_y does the plastic work (1 - b) k d_y |dp|, exact since s u' >= 0 all along the segment (or the
    whole record step, clear_step) just taken."""
    branch, dy, offset, hardening, stiffness, plastic = (yld.branch, yld.yield_drift, yld.offset, yld.hardening,
                                                         yld.stiffness, yld.plastic)
    for i in range(branch.shape[0]):
        if branch[i] != BRANCH_ELASTIC:
            p_new = storey_drift(q, i) - branch[i] * dy[i]
            work = (1.0 - hardening[i]) * stiffness[i] * dy[i] * branch[i] * (p_new - offset[i])
            plastic[i] += work
            diag[D_PLASTIC] += work
            offset[i] = p_new
