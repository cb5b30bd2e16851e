"""The bootstrap the stages judging over record suites share: resamples of whole records (both components of a
record together, as they are not independent)."""

from __future__ import annotations

import numpy as np


def cluster_draws(statistic, clusters: np.ndarray, samples: int, seed: int) -> np.ndarray:
    """`statistic` of each of `samples` resamples: the positions of whole clusters drawn with replacement, as many
    clusters as there are."""
    ids = np.unique(clusters)
    members = [np.flatnonzero(clusters == c) for c in ids]
    rng = np.random.default_rng(seed)
    return np.array([statistic(np.concatenate([members[i] for i in rng.integers(0, len(ids), len(ids))]))
                     for _ in range(samples)])
