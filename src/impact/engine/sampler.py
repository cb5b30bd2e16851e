"""Dense output: the state at requested times, from the closed form of the segment that holds them.

Scene runs take a sorted array of times; as each segment passes them, its
closed form is evaluated there (:func:`sample_segment`).  For the paper's
one-storey kernel, :func:`paper_free_flight` and :func:`paper_state` rebuild
the free flight that starts from a recorded post-impact state, which is what
the virtual test rig samples between impacts.  Either way the samples are
exact to round-off, not interpolated.
"""

from __future__ import annotations

from numba import njit

from impact.engine import paper_loop as K
from impact.engine.segment import state_at


@njit(cache=True)
def sample_segment(kap, C, P, t, tau, ts, its, samples, qs, vs):
    """Dense output: the state at every requested time in [t, t + tau]; returns the next index."""
    nfull = C.shape[0]
    while its < ts.shape[0] and ts[its] <= t + tau:
        state_at(kap, C, P, max(ts[its] - t, 0.0), qs, vs)
        for i in range(nfull):
            samples[its, i] = qs[i]
            samples[its, nfull + i] = vs[i]
        its += 1
    return its


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
