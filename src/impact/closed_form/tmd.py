"""Tuned mass damper (TMD): the linear reference of the impact-damper study.

Implements ``model.md``, section "Tuned mass damper (TMD)"::

    M x'' + C x' + K x + c_t (x' - y') + k_t (x - y) = F0 sin(Omega t)
    m y'' + c_t (y' - x') + k_t (y - x) = 0

Model units (``model.md``, "Symbols and scaling"): omega = sqrt(K/M) = 1, M = 1,
the force enters as the static deflection ``force_ratio`` = F0/K; r = Omega/omega,
beta = C/(2 M omega), mu = m/M, f = omega_t/omega with omega_t = sqrt(k_t/m) and
beta_t = c_t/(2 m omega_t).  Divided by M the equations read

    x'' + 2 beta x' + x + mu [2 beta_t f (x' - y') + f^2 (x - y)] = force_ratio sin(r t)
    y'' + 2 beta_t f (y' - x') + f^2 (y - x) = 0

With h = f^2 + 2 i beta_t f r the steady state x = Im(X e^{i r t}), y = Im(Y e^{i r t}) is

    Den = (1 - r^2 + 2 i beta r)(h - r^2) - mu r^2 h
    X = force_ratio (h - r^2) / Den,     Y = force_ratio h / Den

(written without dividing by h - r^2, so an undamped TMD at r = f gives X = 0
rather than 0/0).

Den Hartog's tuning (:func:`den_hartog`) is the study's design of a building's TMD
(:func:`tuned_for`); the numerical minimax and the curve's true peak are in
:mod:`impact.closed_form.tmd_minimax`, apart, because they need scipy's optimisers
and every job that designs a TMD would otherwise load them.
"""

from __future__ import annotations

import math

import numpy as np

from impact.model.building import Building
from impact.model.kinds import TMD
from impact.model.params import ParameterError
from impact.model.scene import Damper

# --------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------

def check_ranges(mu=None, beta=None, f=None, beta_t=None, force_ratio=None, *, mu_positive=False):
    """Refuse a TMD parameter outside its range (ParameterError naming it and the range); None skips one."""
    checks = []
    if mu is not None:
        checks.append(("mu", mu, (mu > 0) if mu_positive else (mu >= 0), "(0, inf)" if mu_positive else "[0, inf)"))
    if beta is not None:
        checks.append(("beta", beta, 0 <= beta < 1, "[0, 1)"))
    if f is not None:
        checks.append(("f", f, f > 0, "(0, inf)"))
    if beta_t is not None:
        checks.append(("beta_t", beta_t, beta_t >= 0, "[0, inf)"))
    if force_ratio is not None:
        checks.append(("force_ratio", force_ratio, force_ratio > 0, "(0, inf)"))
    for name, value, ok, allowed in checks:
        value = float(value)
        if not (math.isfinite(value) and ok):
            raise ParameterError(f"{name} = {value!r} is out of range: allowed {allowed}")


# --------------------------------------------------------------------------
# frequency response
# --------------------------------------------------------------------------

def tmd_response(r, mu, beta, f, beta_t, force_ratio=0.096):
    """Complex steady-state amplitudes (X, Y) of main mass and TMD mass.

    x(t) = Im(X e^{i r t}), y(t) = Im(Y e^{i r t}) for the force
    force_ratio * sin(r t) (model units, M = 1, omega = 1).  Vectorised over r.
    """
    check_ranges(mu, beta, f, beta_t, force_ratio)
    r = np.asarray(r, dtype=float)
    r2 = r * r
    h = f * f + 2j * beta_t * f * r
    den = (1.0 - r2 + 2j * beta * r) * (h - r2) - mu * r2 * h
    with np.errstate(divide="ignore", invalid="ignore"):
        X = force_ratio * (h - r2) / den
        Y = force_ratio * h / den
    return X, Y


def tmd_amplitude(r, mu, beta, f, beta_t, force_ratio=0.096):
    """Main-mass steady-state amplitude |X| (exact, 2-DOF frequency response).

    Vectorised over r; a scalar r gives a float.  mu = 0 is the bare structure
    force_ratio / sqrt((1 - r^2)^2 + (2 beta r)^2).
    """
    X, _ = tmd_response(r, mu, beta, f, beta_t, force_ratio)
    amp = np.abs(X)
    return float(amp) if amp.ndim == 0 else amp


def tmd_sweep_x_max(r_grid, mu, beta, f, beta_t, force_ratio):
    """Largest amplitude over the given frequency grid (the paper's sweep protocol).

    This is what the paper's sweep measures: max over r in ``r_grid`` of
    |X(r)|.  It is <= :func:`~impact.closed_form.tmd_minimax.tmd_peak` (the curve's true maximum); the two
    differ when the peak lies between grid points or outside the grid's range.
    """
    r_grid = np.asarray(r_grid, dtype=float)
    if r_grid.size == 0:
        raise ParameterError("r_grid is empty")
    return float(np.max(tmd_amplitude(r_grid, mu, beta, f, beta_t, force_ratio)))


# --------------------------------------------------------------------------
# classical tunings
# --------------------------------------------------------------------------

def den_hartog(mu):
    """Den Hartog's fixed-point tuning for an undamped structure.

    f = 1/(1 + mu), beta_t = sqrt(3 mu / (8 (1 + mu)^3)); ``amplification`` =
    sqrt(1 + 2/mu) is the common height of the two fixed points (amplitude over
    force_ratio; multiply by force_ratio for the amplitude).  It is a lower
    bound of the largest peak, not the largest peak itself (see module doc).
    """
    check_ranges(mu=mu, mu_positive=True)
    return {
        "f": 1.0 / (1.0 + mu),
        "beta_t": math.sqrt(3.0 * mu / (8.0 * (1.0 + mu) ** 3)),
        "amplification": math.sqrt(1.0 + 2.0 / mu),
    }


def first_modal_mass(building: Building) -> float:
    """A building's first modal mass, its mode shape scaled to 1 at the roof."""
    _, phi = building.modes()
    shape = phi[:, 0] / phi[-1, 0]
    return float(shape @ (building.masses * shape))


def tuned_for(building: Building, mass_ratio: float) -> Damper:
    """A TMD of mass_ratio x the building's mass on its roof, Den Hartog-tuned to its first mode (the study's
    design, and impact quake's TMD where its tuning and damping are not given)."""
    mass = mass_ratio * building.total_mass
    tuning = den_hartog(mass / first_modal_mass(building))
    return Damper(TMD, mass=mass, tuning=tuning["f"], damping=tuning["beta_t"])
