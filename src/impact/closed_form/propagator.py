"""The exact discrete propagator of a linear building under a ground-acceleration record.

Between two samples a record is linear, so the motion over a step is the matrix exponential of the building's
first-order system augmented by the acceleration and its slope (Van Loan's first-order hold): exact to the
exponential's round-off, with none of the engine's modal rows.  The benchmarks time it as the floor a sample's
cost could reach; the tests read it as an independent solution of the same building.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from impact.model.building import Building


def first_order_hold(building: Building, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A, B0, B1) with x_{k+1} = A x_k + B0 a_k + B1 a_{k+1}, x = (q, q') of M q'' + C q' + K q = -M 1 a(t)."""
    n = building.storeys
    m_inv = np.diag(1.0 / building.masses)
    flow = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ building.stiffness, -m_inv @ building.damping]])
    aug = np.zeros((2 * n + 2, 2 * n + 2))
    aug[: 2 * n, : 2 * n] = flow
    aug[n : 2 * n, 2 * n] = -1.0
    aug[2 * n, 2 * n + 1] = 1.0
    e = expm(aug * dt)
    b1 = e[: 2 * n, 2 * n + 1] / dt
    return e[: 2 * n, : 2 * n].copy(), e[: 2 * n, 2 * n] - b1, b1


def final_state(building: Building, accel: np.ndarray, dt: float) -> np.ndarray:
    """x = (q, q') after the whole record, from rest."""
    a_mat, b0, b1 = first_order_hold(building, dt)
    x = np.zeros(2 * building.storeys)
    for k in range(len(accel) - 1):
        x = a_mat @ x + b0 * accel[k] + b1 * accel[k + 1]
    return x
