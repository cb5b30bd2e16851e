"""Shear buildings: floor masses, storey stiffnesses and damping, and storeys that may yield.

Floors are numbered 1 (lowest) to N (roof).  Storey i joins floor i to the
floor below (the ground for i = 1).  Damping is either classical modal
damping with one ratio in every mode, or given as a matrix.  A building is
elastic unless given yield drifts (Building.yielding): then each storey is
bilinear with kinematic hardening, and P-delta may act on it (docs/model.md,
"Buildings that yield").  Units are the
caller's: model units for the paper's harmonic study (M = 1, K = 1), SI
(kg, N/m, s) for ground motion, where only ratios of masses matter to the
relative response.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.linalg import eigh

from impact.model.params import G_GRAV, ParameterError, _check, check_integer


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


def _checked_floors(masses, storey_stiffness) -> tuple[np.ndarray, np.ndarray]:
    """Floor masses and storey stiffnesses as float arrays, refused by name unless one positive value each."""
    m = _float_array("masses", masses)
    k = _float_array("storey_stiffness", storey_stiffness)
    if m.ndim != 1 or len(m) < 1:
        raise ParameterError("masses must be a list of at least one floor mass")
    if k.shape != m.shape:
        raise ParameterError(f"storey_stiffness has {len(k)} values for {len(m)} floors: give one per storey")
    for i, (mi, ki) in enumerate(zip(m, k), start=1):
        _check(f"masses[{i}]", mi, 0.0, 1e15, lo_open=True)
        _check(f"storey_stiffness[{i}]", ki, 0.0, 1e18, lo_open=True)
    return m, k


def _checked_damping(damping, n: int) -> np.ndarray:
    """An n x n damping matrix, symmetric and positive semi-definite to round-off of its largest entry.

    The test is on the whole matrix's scale, not entry by entry: modal damping of floors whose masses
    differ by 1e3 has off-diagonal entries of pure round-off, asymmetric relative to themselves.
    """
    c = np.atleast_2d(_float_array("damping", damping))
    if c.shape != (n, n):
        raise ParameterError(f"damping must be a {n} x {n} matrix")
    if not np.all(np.isfinite(c)):
        raise ParameterError("damping must be finite")
    scale = np.max(np.abs(c))
    if np.max(np.abs(c - c.T)) > 1e-12 * scale or np.min(np.linalg.eigvalsh(0.5 * (c + c.T))) < -1e-12 * scale:
        raise ParameterError("damping must be a symmetric positive semi-definite matrix")
    return c


def _float_array(name: str, values) -> np.ndarray:
    try:
        return np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be numbers, got {values!r}") from None


def _checked_per_storey(name: str, values, n: int, lo: float, hi: float, *, hi_open=False) -> np.ndarray:
    """One value per storey (or one for all), each in (lo, hi], refused by name and storey."""
    a = _float_array(name, values)
    if a.shape == (1,):
        a = np.full(n, a[0])
    if a.shape != (n,):
        raise ParameterError(f"{name} has {len(a)} values for {n} storeys: give one, or one per storey")
    for i, x in enumerate(a, start=1):
        _check(f"{name}[{i}]", x, lo, hi, lo_open=True, hi_open=hi_open)
    return a


@dataclass(frozen=True, eq=False)
class Building:
    """A shear building: floor masses (N,), storey stiffnesses (N,), damping matrix (N, N).

    Yielding (all None / 0 / False: elastic, as every building before yielding was added):
    yield_drift (N,): each storey's drift at first yield, in metres (its yield force is k d_y, Steel01's Fy);
    hardening: the post-yield stiffness ratio b in [0, 1), one for every storey;
    storey_height (N,): each storey's height, which P-delta and the collapse limit need;
    p_delta: gravity's P-delta on every storey, a geometric stiffness -P_i / h_i with P_i the weight above it.
    """

    masses: np.ndarray
    storey_stiffness: np.ndarray
    damping: np.ndarray
    zeta: float = math.nan
    yield_drift: np.ndarray | None = None
    hardening: float = 0.0
    storey_height: np.ndarray | None = None
    p_delta: bool = False

    def __post_init__(self):
        m, k = _checked_floors(self.masses, self.storey_stiffness)
        c = _checked_damping(self.damping, len(m))
        object.__setattr__(self, "masses", m)
        object.__setattr__(self, "storey_stiffness", k)
        object.__setattr__(self, "damping", c)
        self._check_yielding(len(m))

    def _check_yielding(self, n: int) -> None:
        if self.yield_drift is not None:
            object.__setattr__(self, "yield_drift", _checked_per_storey("yield_drift", self.yield_drift, n, 0.0, 1e3))
        _check("hardening", self.hardening, 0.0, 1.0, hi_open=True)
        if self.storey_height is not None:
            object.__setattr__(self, "storey_height",
                               _checked_per_storey("storey_height", self.storey_height, n, 0.0, 1e4))
        if self.p_delta and self.storey_height is None:
            raise ParameterError("p_delta needs storey_height: P-delta's stiffness is P / h")
        if (self.yield_drift is None) and self.hardening != 0.0:
            raise ParameterError("hardening needs yield_drift: an elastic building has no post-yield branch")
        if self.yield_drift is not None and self.hardening == 0.0 and not self.p_delta:
            # a perfectly plastic storey leaves the floors above it a rigid mode, which only damping keeps finite
            if np.min(np.linalg.eigvalsh(self.damping)) <= 1e-12 * np.max(np.abs(self.damping)):
                raise ParameterError("hardening = 0 without P-delta needs damping in every mode (zeta > 0): "
                                     "a yielding storey would leave an undamped rigid mode")

    def yielding(self, yield_drift, hardening: float = 0.0, storey_height=None, p_delta: bool = False) -> "Building":
        """This building with storeys that yield: yield drifts in metres (one, or one per storey), the hardening
        ratio b in [0, 1), storey heights in metres (for P-delta and the collapse limit), P-delta on or off."""
        return replace(self, yield_drift=yield_drift, hardening=float(hardening), storey_height=storey_height,
                       p_delta=bool(p_delta))

    def geometric_stiffness(self, carried=None, gravity: float = G_GRAV) -> np.ndarray:
        """P-delta's stiffness P_i / h_i of every storey, storey 1 first (zeros without P-delta): P_i is the weight,
        at `gravity`, of the masses on every floor the storey carries; `carried` gives them per floor (a scene adds
        its dampers' to the floors' own, which are the default)."""
        if not self.p_delta:
            return np.zeros(self.storeys)
        carried = self.masses if carried is None else carried
        return np.cumsum(carried[::-1])[::-1] * gravity / self.storey_height

    def stability_coefficients(self, carried=None, gravity: float = G_GRAV) -> np.ndarray:
        """Every storey's stability coefficient theta = P / (k h), ASCE 7's (zeros without P-delta), storey 1 first;
        `carried` and `gravity` as in geometric_stiffness."""
        return self.geometric_stiffness(carried, gravity) / self.storey_stiffness

    @property
    def is_elastic(self) -> bool:
        """Whether every storey is linear and without P-delta: the engine runs it exactly as an elastic building."""
        return self.yield_drift is None and not self.p_delta

    @classmethod
    def uniform(cls, storeys: int, period_s: float, zeta: float, floor_mass: float = 1.0e5) -> "Building":
        """N equal floors and storeys, stiffness set so that the fundamental period is T1, zeta in every mode."""
        n = check_integer("storeys", storeys, 1, 200)
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
        """Given floor masses and storey stiffnesses; damping as a modal ratio or as storey dashpots.

        masses: each floor's mass, floor 1 (the lowest) first (kg in SI); storey_stiffness: each storey's lateral
        stiffness, storey 1 (floor 1 to the ground) first (N/m); zeta: one modal damping ratio for every mode, or
        storey_damping: each storey's dashpot (N s/m), in the same order.  Both arrays as long as the storeys.
        """
        m, k = _checked_floors(masses, storey_stiffness)
        if (zeta is None) == (storey_damping is None):
            raise ParameterError("give exactly one of zeta (modal damping ratio) and storey_damping (dashpots)")
        if zeta is not None:
            _check("zeta", zeta, 0.0, 1.0, hi_open=True)
            return cls(m, k, modal_damping(m, _storey_matrix(k), zeta), zeta=float(zeta))
        c = _float_array("storey_damping", storey_damping)
        if c.shape != m.shape:
            raise ParameterError(f"storey_damping has {len(c)} values for {len(m)} floors: give one per storey")
        for i, ci in enumerate(c, start=1):
            _check(f"storey_damping[{i}]", ci, 0.0, 1e18)
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
        out = {"storeys": self.storeys, "masses": self.masses.tolist(),
               "storey_stiffness": self.storey_stiffness.tolist(), "zeta": self.zeta,
               "period1_s": self.period1}
        if not self.is_elastic:
            out.update(yield_drift=None if self.yield_drift is None else self.yield_drift.tolist(),
                       hardening=self.hardening, p_delta=self.p_delta,
                       storey_height=None if self.storey_height is None else self.storey_height.tolist())
        return out
