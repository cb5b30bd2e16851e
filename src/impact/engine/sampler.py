"""Dense output: the state at requested times, from the closed form of the segment that holds them.

Scene runs take a sorted array of times; as each segment passes them, its
closed form is evaluated there (:func:`sample_segment`).  For the paper's
one-storey kernel, :func:`paper_samples` runs the loop over chunks of the sample
times and rebuilds, between the impacts each chunk records, the free flight from
the post-impact state (:func:`paper_free_flight`, :func:`paper_state`): the
validation's model sampled at the sensor's rate.  Either way the samples are
exact to round-off, not interpolated.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from impact.engine import layout as L
from impact.engine import paper_loop as K
from impact.engine.events import PEAK_NOISE
from impact.engine.segment import poly_bound, state_from_exp


@njit(cache=True)
def sample_segment(kap, C, P, t, tau, ts, its, samples, qs, vs):
    """Dense output: the state at every requested time in [t, t + tau], and each position's round-off; returns
    the next index.  samples' row: positions, velocities, then the positions' round-off (row_roundoff)."""
    nfull = C.shape[0]
    ek = np.empty(kap.shape[0], dtype=np.complex128)
    while its < ts.shape[0] and ts[its] <= t + tau:
        at = max(ts[its] - t, 0.0)
        for k in range(kap.shape[0]):
            ek[k] = np.exp(kap[k] * at)
        state_from_exp(kap, ek, C, P, at, qs, vs)
        for i in range(nfull):
            samples[its, i] = qs[i]
            samples[its, nfull + i] = vs[i]
            samples[its, 2 * nfull + i] = row_roundoff(ek, C, P, i, at)
        its += 1
    return its


@njit(cache=True)
def row_roundoff(ek, C, P, i, tau):
    """The round-off of row i's value at tau (ek = exp(kap tau)): its terms' sizes times events.PEAK_NOISE, as
    the peak search counts a row's.  Where the terms cancel (a slow mode's particular solution of metres against
    its exponential, to a motion of micrometres) it is far above the value's last bit."""
    size = poly_bound(P[i], 0, tau)
    for k in range(ek.shape[0]):
        size += abs(C[i, k] * ek[k])
    return PEAK_NOISE * size


@njit(cache=True)
def paper_free_flight(kap, cx, cy, poly, z, t0, p, pid):
    """Coefficients of the paper kernel's frictionless free flight from state z = (x, x', y, y') at time t0.

    kap, cx, cy: complex arrays of impact.engine.paper_loop.NT slots, poly: 2 floats, all written in place;
    p: the kernel's parameter vector; pid: the PID's eigen-data, or None for the CID.
    """
    K.build_free_flight(kap, cx, cy, poly, z, t0, p, pid, None, 0)


@njit(cache=True)
def paper_state(kap, cx, cy, poly, tau, z):
    """(x, x', y, y') at time tau after the start of a free flight of paper_free_flight, into z."""
    K.flight_state(kap, cx, cy, poly[0], poly[1], tau, z)


@njit(cache=True)
def _chunk_dense(call, z, code, ta, tb, ts, zs, i0, i1):
    """One call of the paper loop over [ta, tb]; the state at ts[i0:i1] in (ta, tb] rebuilt from its impacts.

    Between impacts the loop's motion is the closed-form free flight from the post-impact state, so the samples
    are exact.  Returns (new contact code, ok): ok = False when the chunk holds a sticking episode (a release is
    not recorded), more impacts than ``call.rec`` holds or a stop of the event guard; then the caller runs it
    again sample by sample.
    """
    p, pid, rec, diag = call.p, call.pid, call.rec, call.diag
    p[L.P_T0] = ta
    p[L.P_TEND] = tb
    code_new = K.run(p, z, code, pid, None, rec, diag, call.z_out)
    nr = int(diag[L.D_NREC])
    if code % 10 != L.MODE_FREE or nr >= rec.shape[0] or diag[L.D_CAP] > 0.0:
        return code_new, False
    for j in range(nr):
        if rec[j, L.R_STUCK] > 0.0:
            return code_new, False
    kap = np.zeros(K.NT, dtype=np.complex128)
    cx = np.zeros(K.NT, dtype=np.complex128)
    cy = np.zeros(K.NT, dtype=np.complex128)
    poly = np.zeros(2)
    zf = z.copy()
    zt = np.zeros(4)
    t_seg = ta
    half = 0.5 * p[L.P_GAP]
    j = 0
    paper_free_flight(kap, cx, cy, poly, zf, t_seg, p, pid)
    for i in range(i0, i1):
        while j < nr and rec[j, L.R_T] <= ts[i]:
            side = rec[j, L.R_SIDE]
            zf[0] = rec[j, L.R_X]
            zf[1] = rec[j, L.R_V1]
            zf[2] = rec[j, L.R_X] + side * half
            zf[3] = rec[j, L.R_W1]
            t_seg = rec[j, L.R_T]
            paper_free_flight(kap, cx, cy, poly, zf, t_seg, p, pid)
            j += 1
        paper_state(kap, cx, cy, poly, ts[i] - t_seg, zt)
        for k in range(4):
            zs[i, k] = zt[k]
    return code_new, True


@njit(cache=True)
def _advance(call, z, code, ta, tb):
    """One call of the paper loop from ta to tb, the state moved to tb; returns (contact code, stopped early)."""
    p, diag = call.p, call.diag
    p[L.P_T0] = ta
    p[L.P_TEND] = tb
    code = K.run(p, z, code, call.pid, None, call.rec, diag, call.z_out)
    capped = diag[L.D_CAP] > 0.0 or diag[L.D_TEND] < tb
    for k in range(4):
        z[k] = call.z_out[k]
    return code, capped


@njit(cache=True)
def _keep_records(rec, diag, kept, nkept):
    """Append the call's impact records to kept while it has room; returns the new count of impacts."""
    for j in range(int(diag[L.D_NREC])):
        if nkept < kept.shape[0]:
            for c in range(rec.shape[1]):
                kept[nkept, c] = rec[j, c]
        nkept += 1
    return nkept


@njit(cache=True)
def _hold(z, zs, i):
    for k in range(4):
        zs[i, k] = z[k]


@njit(cache=True)
def paper_samples(call, z, code, t, ts, zs, kept, out, chunk):
    """The paper loop's dense output: run it from t through the sorted sample times ts, (x, x', y, y') at each
    into zs, every impact record into kept (as far as it holds them); z: the state at t, left at the last sample.

    The loop runs over chunks of ``chunk`` samples; inside a chunk the samples are rebuilt exactly from its
    impact records (:func:`_chunk_dense`), or, if the chunk holds a sticking episode, by one call of the loop per
    sample interval.  out = (impacts, whether the event guard stopped a call, final contact code).
    """
    rec, diag, zo = call.rec, call.diag, call.z_out
    nkept = 0
    cap = 0.0
    n = ts.shape[0]
    i = 0
    while i < n and ts[i] <= t:
        _hold(z, zs, i)
        i += 1
    if i < n and ts[i] > t:
        # settle: one call up to the first sample
        code, capped = _advance(call, z, code, t, ts[i])
        if capped:
            cap = 1.0
        t = ts[i]
        _hold(z, zs, i)
        i += 1
    while i < n:
        i1 = min(i + chunk, n)
        tb = ts[i1 - 1]
        code_new, ok = _chunk_dense(call, z, code, t, tb, ts, zs, i, i1)
        if ok:
            nkept = _keep_records(rec, diag, kept, nkept)
            code = code_new
            for k in range(4):
                z[k] = zo[k]
            t = tb
        else:
            for ii in range(i, i1):
                if ts[ii] > t:
                    code, capped = _advance(call, z, code, t, ts[ii])
                    nkept = _keep_records(rec, diag, kept, nkept)
                    if capped:
                        cap = 1.0
                    t = ts[ii]
                _hold(z, zs, ii)
        i = i1
    out[0] = nkept
    out[1] = cap
    out[2] = code
