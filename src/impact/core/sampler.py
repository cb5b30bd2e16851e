"""Dense output: the state of every degree of freedom at requested times.

A run is given a sorted array of times; as each segment passes them, its
closed form is evaluated there.  The samples are therefore exact (to
round-off), not interpolated, and cost nothing when none are asked for.
"""

from __future__ import annotations

from numba import njit

from .segment import state_at


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
