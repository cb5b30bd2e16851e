"""Linear shear buildings: floor masses, storey stiffnesses and damping.

Floors are numbered 1 (lowest) to N (roof).  Storey i joins floor i to the
floor below (the ground for i = 1).  Damping is either classical modal
damping with one ratio in every mode, or given as a matrix.  Units are the
caller's: model units for the paper's harmonic study (M = 1, K = 1), SI
(kg, N/m, s) for ground motion, where only ratios of masses matter to the
relative response.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import eigh

from impact.model.params import ParameterError, _check


def _storey_matrix(k: np.ndarray) -> np.ndarray:
    """Tridiagonal stiffness (or damping) matrix of storey springs k[i] between floors i-1 and i."""
    n = len(k)
    mat = np.zeros((n, n))
    for i in range(n):
        mat[i, i] += k[i]
        if i + 1 < n:
            mat[i, i] += k[i + 1]
            mat[i, i + 1] -= k[i + 1]
            mat[i + 1, i] -= k[i + 1]
    return mat


def modal_damping(mass: np.ndarray, stiffness: np.ndarray, zeta: float) -> np.ndarray:
    """Classical damping matrix with ratio zeta in every mode: C = M Phi diag(2 zeta w_n) Phi^T M."""
    w2, phi = eigh(stiffness, np.diag(mass))  # mass-normalised: Phi^T M Phi = I
    m = np.diag(mass)
    return m @ phi @ np.diag(2.0 * zeta * np.sqrt(w2)) @ phi.T @ m


@dataclass(frozen=True, eq=False)
class Building:
    """A shear building: floor masses (N,), storey stiffnesses (N,), damping matrix (N, N)."""

    masses: np.ndarray
    storey_stiffness: np.ndarray
    damping: np.ndarray
    zeta: float = math.nan

    def __post_init__(self):
        m = np.atleast_1d(np.asarray(self.masses, dtype=float))
        k = np.atleast_1d(np.asarray(self.storey_stiffness, dtype=float))
        c = np.atleast_2d(np.asarray(self.damping, dtype=float))
        if m.ndim != 1 or len(m) < 1:
            raise ParameterError("masses must be a list of at least one floor mass")
        if k.shape != m.shape:
            raise ParameterError(f"storey_stiffness has {len(k)} values for {len(m)} floors: give one per storey")
        if c.shape != (len(m), len(m)):
            raise ParameterError(f"damping must be a {len(m)} x {len(m)} matrix")
        for i, (mi, ki) in enumerate(zip(m, k), start=1):
            _check(f"masses[{i}]", mi, 0.0, 1e15, lo_open=True)
            _check(f"storey_stiffness[{i}]", ki, 0.0, 1e18, lo_open=True)
        if not np.allclose(c, c.T, rtol=1e-12, atol=0.0) or np.min(np.linalg.eigvalsh(c)) < -1e-12 * np.max(np.abs(c)):
            raise ParameterError("damping must be a symmetric positive semi-definite matrix")
        object.__setattr__(self, "masses", m)
        object.__setattr__(self, "storey_stiffness", k)
        object.__setattr__(self, "damping", c)

    @classmethod
    def uniform(cls, storeys: int, period_s: float, zeta: float, floor_mass: float = 1.0e5) -> "Building":
        """N equal floors and storeys, stiffness set so that the fundamental period is T1, zeta in every mode."""
        n = int(storeys)
        if n != storeys or not 1 <= n <= 200:
            raise ParameterError(f"storeys = {storeys!r} is out of range: allowed integers [1, 200]")
        _check("period_s", period_s, 0.0, 1e4, lo_open=True)
        _check("zeta", zeta, 0.0, 1.0, lo_open=True, hi_open=True)
        _check("floor_mass", floor_mass, 0.0, 1e15, lo_open=True)
        masses = np.full(n, float(floor_mass))
        unit = _storey_matrix(np.ones(n))
        lam1 = eigh(unit, np.diag(masses), eigvals_only=True)[0]
        k = (2.0 * math.pi / period_s) ** 2 / lam1
        stiff = np.full(n, k)
        return cls(masses, stiff, modal_damping(masses, _storey_matrix(stiff), zeta), zeta=float(zeta))

    @classmethod
    def explicit(cls, masses, storey_stiffness, zeta: float | None = None, storey_damping=None) -> "Building":
        """Given floor masses and storey stiffnesses; damping as a modal ratio or as storey dashpots."""
        m = np.atleast_1d(np.asarray(masses, dtype=float))
        k = np.atleast_1d(np.asarray(storey_stiffness, dtype=float))
        if (zeta is None) == (storey_damping is None):
            raise ParameterError("give exactly one of zeta (modal damping ratio) and storey_damping (dashpots)")
        if zeta is not None:
            _check("zeta", zeta, 0.0, 1.0, hi_open=True)
            return cls(m, k, modal_damping(m, _storey_matrix(k), zeta), zeta=float(zeta))
        c = np.atleast_1d(np.asarray(storey_damping, dtype=float))
        if c.shape != m.shape:
            raise ParameterError(f"storey_damping has {len(c)} values for {len(m)} floors: give one per storey")
        return cls(m, k, _storey_matrix(c))

    @classmethod
    def paper(cls, beta: float) -> "Building":
        """The paper's structure in model units: M = 1, K = 1, C = 2 beta (omega = 1)."""
        _check("beta", beta, 0.0, 1.0, hi_open=True)
        return cls(np.ones(1), np.ones(1), np.array([[2.0 * beta]]), zeta=float(beta))

    @property
    def storeys(self) -> int:
        return len(self.masses)

    @property
    def stiffness(self) -> np.ndarray:
        return _storey_matrix(self.storey_stiffness)

    @property
    def total_mass(self) -> float:
        return float(np.sum(self.masses))

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """Circular frequencies (ascending) and mass-normalised mode shapes (columns)."""
        w2, phi = eigh(self.stiffness, np.diag(self.masses))
        return np.sqrt(w2), phi

    @property
    def omega1(self) -> float:
        return float(self.modes()[0][0])

    @property
    def period1(self) -> float:
        return 2.0 * math.pi / self.omega1

    def as_dict(self) -> dict:
        return {"storeys": self.storeys, "masses": self.masses.tolist(),
                "storey_stiffness": self.storey_stiffness.tolist(), "zeta": self.zeta,
                "period1_s": self.period1}
