"""Modal shortcuts of a segment: per-configuration tables that make the hot steps O(modes).

build_segment writes every row of a configuration as C[i, k] = V[r(i), k] w_k,
where V holds the configuration's eigenvectors, w the segment's modal
amplitudes and r(i) the reduced degree of freedom that carries full degree of
freedom i (a unit at rest on its wall rides its floor; a free CID unit has no
exponential part).  Any fixed linear combination of the rows therefore has
exponential coefficients (a^T V)_k w_k, and any fixed quadratic form of the
velocities integrates to a double sum over modes.  Those coefficients depend
on the configuration only, so they are tabulated once per cache slot:

    gvis[k, l] = kap_k kap_l V_k^T C_r V_l   the viscous dissipation, v^T C v
    lmod[k]    = kap_k l_r^T V_k              the load's work, f(t) l^T v
    mvec[m, k] = (a_m^T V)_k (kap_k^2 for an acceleration monitor)
    mbnd[m, k] = |mvec[m, k]| |kap_k|^2       the monitor's curvature bound per |w_k|

A record run then integrates its energy terms and bounds every monitor with
a few multiply-adds per mode instead of assembling rows of every degree of
freedom.  The harmonic load's two extra slots are added where it is present.

Every row is real, so its terms come in conjugate pairs: Re sum_k c_k e^(kap_k t)
equals Re sum_k wt_k c_k e^(kap_k t) with weight 2 on one mode of each pair, 0
on its partner and 1 on a real mode or a pair near critical damping (mode_weights).  Whatever is linear in a
row (its values, derivatives, bounds) is therefore computed on the weighted
half row, with half the exponentials; a product of two rows is not linear,
so its double sum keeps every l and halves only the outer sum over k.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from impact.engine.bundles import ModalTables
from impact.engine.layout import D_STUCKTIME, D_VISC, D_WORK, MODE_FREE, MODE_LOCKED, MON_ACCEL, NPOLY
from impact.engine.segment import poly_at, poly_bound, poly_integral


@njit(cache=True)
def modal_tables(slots, nmax, nmon, nstoreys):
    """Empty per-slot tables for modal_slot (nmax: the largest reduced size; mkey -1: not filled; nstoreys: the
    yielding storeys, 0 for an elastic building)."""
    m2 = 2 * nmax
    return ModalTables(np.full(slots, -1, dtype=np.int64), np.zeros((slots, m2, m2), dtype=np.complex128),
                       np.zeros((slots, m2), dtype=np.complex128),
                       np.zeros((slots, nmon, m2), dtype=np.complex128), np.zeros((slots, nmon, m2)),
                       np.zeros((slots, nstoreys, 2, m2)))


_PAIR_TOL = 1e-9  # two modes are a conjugate pair when they are conjugates to this fraction of |kap|
# below this |Im kap| / |kap| (damping ratio above 0.995) a pair is summed in full: near critical damping
# its two coefficients are large and cancel, and the half row would lose that cancellation
_PAIR_MIN = 0.1


@njit(cache=True)
def mode_weights(kap, wt):
    """Weight 2 on the upper mode of each conjugate pair and 0 on its partner, found by value; 1 elsewhere.

    Pairs are matched explicitly, never guessed from the sign of Im kap alone: the eigenvalues come from a
    complex eigensolver, so a real mode may carry a rounding error in its imaginary part, and it keeps
    weight 1 whatever the sign of that error.  Repeated pairs (identical units) match one to one.
    """
    n = kap.shape[0]
    for k in range(n):
        wt[k] = 1.0
    for k in range(n):
        a = kap[k]
        if not a.imag > _PAIR_MIN * abs(a):
            continue
        partner = -1
        closest = _PAIR_TOL * abs(a)
        for j in range(n):
            if j != k and wt[j] == 1.0 and kap[j].imag < 0.0:
                gap = abs(kap[j] - a.conjugate())
                if gap <= closest:
                    partner = j
                    closest = gap
        if partner >= 0:
            wt[k] = 2.0
            wt[partner] = 0.0


@njit(cache=True)
def halve(c, wt):
    """The weighted half row of c, in place."""
    for k in range(c.shape[0]):
        c[k] = c[k] * wt[k]


@njit(cache=True)
def halve_from_start(kap, c, p, wt):
    """halve, with p's first two terms taking up what halving moves at tau = 0, so that the half row starts
    where the full row does.

    The eigenpairs come from a complex eigensolver, so a pair's coefficients are conjugates only to round-off
    of the basis' condition: in a row of 1e-5 m terms beside a stiff pendulum that is 1.4e-16 m, more than
    twice the contact tolerance.  A contact row that starts off its wall by that much moves each rebound's
    start off the wall and pumps the bounce; the full row (the state) is the one to start from.
    """
    d0 = 0.0
    d1 = 0.0
    for k in range(c.shape[0]):
        ck = c[k]
        w = wt[k]
        if w != 1.0:
            d0 += (1.0 - w) * ck.real
            d1 += (1.0 - w) * (ck * kap[k]).real
        c[k] = ck * w
    p[0] += d0
    p[1] += d1


@njit(cache=True)
def _reduced_index(s, fidx, nf, units, mode, red):
    """red[i]: the reduced degree of freedom that carries full degree of freedom i (-1: a free CID unit)."""
    ufloor = units.floor
    for i in range(red.shape[0]):
        red[i] = -1
    for r in range(fidx.shape[1]):
        i = fidx[s, r]
        if i >= 0:
            red[i] = r
    for j in range(ufloor.shape[0]):
        if mode[j] != MODE_FREE:
            red[nf + j] = red[ufloor[j]]


@njit(cache=True)
def modal_slot(s, key, cache, nf, units, mode, mon_rows, mon_kind, mtab, growth):
    """Fill slot s of the modal tables for configuration `key` (a no-op when they are current).

    growth: the most a growing mode's exponential (Re kap > 0: a storey whose P-delta outweighs its stiffness)
    can reach over a segment, which the run keeps short enough (scene_loop.growth_rate); 1 when none grows."""
    mkey, gvis, lmod, mvec, mbnd, reach = mtab
    if mkey[s] == key:
        return
    nr, lam, vec, cred, fidx, ellr = cache.size, cache.lam, cache.vec, cache.damping, cache.dof, cache.load
    n = nr[s]
    red = np.empty(mon_rows.shape[1], dtype=np.int64)
    _reduced_index(s, fidx, nf, units, mode, red)
    cv = np.zeros((n, 2 * n), dtype=np.complex128)  # C_r V
    for a in range(n):
        for l in range(2 * n):
            acc = 0.0 + 0.0j
            for b in range(n):
                acc += cred[s, a, b] * vec[s, b, l]
            cv[a, l] = acc
    for k in range(2 * n):
        lk = 0.0 + 0.0j
        for r in range(n):
            lk += ellr[s, r] * vec[s, r, k]
        lmod[s, k] = lam[s, k] * lk
        for l in range(2 * n):
            acc = 0.0 + 0.0j
            for a in range(n):
                acc += vec[s, a, k] * cv[a, l]
            gvis[s, k, l] = lam[s, k] * lam[s, l] * acc
    for m in range(mon_rows.shape[0]):
        for k in range(2 * n):
            acc = 0.0 + 0.0j
            for i in range(mon_rows.shape[1]):
                wt = mon_rows[m, i]
                if wt != 0.0 and red[i] >= 0:
                    acc += wt * vec[s, red[i], k]
            if mon_kind[m] == MON_ACCEL:
                acc *= lam[s, k] * lam[s, k]
            mvec[s, m, k] = acc
            mbnd[s, m, k] = abs(acc) * abs(lam[s, k]) ** 2
            if lam[s, k].real > 0.0:
                mbnd[s, m, k] *= growth
    storey_reach(s, n, vec, reach)
    mkey[s] = key


@njit(cache=True)
def storey_reach(s, n, vec, reach):
    """Per yielding storey i and mode k of slot s: the modulus of the storey's drift in the mode (its floor's
    position less the one below's), and the size of the two floors' own parts (|re| + |im| each), on which a
    drift row is rounded (scene_loop._storey_clear).  The floors are the first reduced degrees of freedom."""
    for i in range(reach.shape[1]):
        for k in range(2 * n):
            top = vec[s, i, k]
            below = vec[s, i - 1, k] if i > 0 else 0.0 + 0.0j
            reach[s, i, 0, k] = abs(top - below)
            reach[s, i, 1, k] = abs(top.real) + abs(top.imag) + abs(below.real) + abs(below.imag)


@njit(cache=True)
def amplitude_moduli(n, wc, aw):
    """|w_k| of the segment's 2n modal amplitudes (wc[2n:4n], build_segment's scratch)."""
    for k in range(2 * n):
        aw[k] = abs(wc[2 * n + k])


@njit(cache=True)
def monitor_row(w, s, m, n, monitors, r0, r1, harmonic):
    """Coefficient row of monitor m, into w.cm and w.pm, from the modal amplitudes wc[2n:4n] (the harmonic slots
    from C); w: bundles.SegmentWork."""
    wc, C, kap, P, cm, pm, mvec = w.wc, w.C, w.kap, w.P, w.cm, w.pm, w.mvec
    mon_rows, mon_kind, mon_rec = monitors.rows, monitors.kind, monitors.record_coef
    nt = kap.shape[0]
    for k in range(nt):
        cm[k] = 0.0
    for k in range(2 * n):
        cm[k] = mvec[s, m, k] * wc[2 * n + k]
    for k in range(NPOLY):
        pm[k] = 0.0
    for i in range(P.shape[0]):
        wt = mon_rows[m, i]
        if wt != 0.0:
            for k in range(NPOLY):
                pm[k] += wt * P[i, k]
            if harmonic:
                for k in range(nt - 2, nt):
                    cm[k] += wt * C[i, k]
    if mon_kind[m] == MON_ACCEL:
        if harmonic:
            for k in range(nt - 2, nt):
                cm[k] = cm[k] * kap[k] * kap[k]
        pm[0] = 2.0 * pm[2] + mon_rec[m] * r0
        pm[1] = 6.0 * pm[3] + mon_rec[m] * r1
        pm[2] = 0.0
        pm[3] = 0.0


@njit(cache=True)
def end_values(ek, c, p, big_t):
    """h(0) and h(T) of a row, from ek = exp(kap T)."""
    h0 = p[0]
    h1 = poly_at(p, big_t)
    for k in range(c.shape[0]):
        ck = c[k]
        h0 += ck.real
        h1 += ck.real * ek[k].real - ck.imag * ek[k].imag
    return h0, h1


@njit(cache=True)
def curvature_bound(w, s, m, n, big_t, harmonic):
    """Bound on |h''| over [0, T] of monitor m's (halved) row w.cm, w.pm: the tabulated modal part, then the rest."""
    aw, wt, cm, pm, kpow = w.aw, w.wt, w.cm, w.pm, w.kpow
    mbnd = w.mbnd
    acc = 0.0
    for k in range(2 * n):
        acc += wt[k] * mbnd[s, m, k] * aw[k]
    if harmonic:
        nt = cm.shape[0]
        for k in range(nt - 2, nt):
            acc += abs(cm[k]) * kpow[2, k]
    return acc + poly_bound(pm, 2, big_t)


@njit(cache=True)
def square_integral(c, p, wt, pair, single, big_t):
    """Integral over [0, T] of h^2 for a full (not halved) row h, the outer sums halved by the weights."""
    quad = 0.0 + 0.0j
    cross = 0.0 + 0.0j
    for k in range(c.shape[0]):
        if wt[k] == 0.0 or (c[k].real == 0.0 and c[k].imag == 0.0):
            continue
        inner = 0.0 + 0.0j
        for l in range(c.shape[0]):
            inner += pair[k, l] * c[l]
        poly = 0.0 + 0.0j
        for m in range(NPOLY):
            poly += p[m] * single[k, m]
        quad += wt[k] * c[k] * inner
        cross += wt[k] * c[k] * poly
    return quad.real + 2.0 * cross.real + poly_integral(p, p, big_t)


@njit(cache=True)
def integrate_modal(w, s, n, tau, units, record, r0, r1, from_state):
    """Exact work of a record load, viscous dissipation and stuck time over [0, tau], from the modal tables.

    w.wc: build_segment's scratch, with the modal amplitudes w in wc[2n:4n]; w.v: the state's velocities at the
    segment's start; cu1: scratch of the reduced size; wt: the segment's mode weights (mode_weights), which halve
    the sums over k; single, ramp: integral_tables and ramp_tables over tau; pu: (2, NPOLY) scratch; all of them
    fields of w (bundles.SegmentWork).  from_state: the load's work in the ramp form too, from the state's
    velocities (a yielding building's, whose state is advanced from itself while a storey yields:
    segment.flow_change); an elastic building's is taken term by term, as it always was, so that its numbers stay
    what they were.
    """
    cu1, wt, mode, load_vec, P, pu, diag = w.cu1, w.wt, w.mode, w.load_vec, w.P, w.pu, w.diag
    ramp, single, gvis, lmod, lam, vec, cred = w.ramp, w.single, w.gvis, w.lmod, w.lam, w.vec, w.damping
    wc, v, dof = w.wc, w.v, w.dof
    W = 2 * n
    if tau > 0.0:
        if record is not None:
            # work: f = r0 + r1 tau against l^T v, the modal part, then the polynomial parts of every row
            # (from_state: l^T v = l^T v0 + sum_k lmod_k w_k (exp(kap_k tau) - 1) + the rows' higher powers, the
            # ramp form, whose terms are the size of the velocity's change, as the dissipation's below)
            m0 = NPOLY if from_state else 0
            acc = 0.0 + 0.0j
            for k in range(2 * n):
                if wt[k] != 0.0:
                    acc += wt[k] * lmod[s, k] * wc[W + k] * (r0 * single[k, m0] + r1 * single[k, m0 + 1])
            for k in range(NPOLY):
                pu[0, k] = 0.0
                pu[1, k] = 0.0
            pu[1, 0] = r0
            pu[1, 1] = r1
            for i in range(P.shape[0]):
                li = load_vec[i]
                if li != 0.0:
                    pu[0, 0] += li * (v[i] if from_state else P[i, 1])
                    pu[0, 1] += li * 2.0 * P[i, 2]
                    pu[0, 2] += li * 3.0 * P[i, 3]
            diag[D_WORK] += acc.real + poly_integral(pu[0], pu[1], tau)
        # viscous dissipation of v_r = v0 + sum_k V_k kap_k w_k (exp(kap_k tau) - 1) in the reduced damping C_r:
        # the ramp form (segment.ramp_tables), from the state's velocities v0, not the modes' and the particular
        # solution's, which cancel to them (to the square of that in a product)
        quad = 0.0 + 0.0j
        for k in range(2 * n):
            if wt[k] == 0.0:
                continue
            inner = 0.0 + 0.0j
            for l in range(2 * n):
                inner += gvis[s, k, l] * ramp[k, l] * wc[W + l]
            quad += wt[k] * wc[W + k] * inner
        steady = 0.0
        for a in range(n):
            ca = 0.0
            for b in range(n):
                ca += cred[s, a, b] * v[dof[s, b]]
            cu1[a] = ca
            steady += v[dof[s, a]] * ca
        cross = 0.0 + 0.0j
        for k in range(2 * n):
            if wt[k] == 0.0:
                continue
            hk = 0.0 + 0.0j
            for a in range(n):
                hk += vec[s, a, k] * cu1[a]
            cross += wt[k] * wc[W + k] * lam[s, k] * hk * single[k, NPOLY]
        diag[D_VISC] += quad.real + 2.0 * cross.real + steady * tau
    for j in range(mode.shape[0]):
        if mode[j] != MODE_FREE and mode[j] != MODE_LOCKED:
            diag[D_STUCKTIME] += tau
