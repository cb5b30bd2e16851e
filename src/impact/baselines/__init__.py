"""Baseline integrators the exact event-driven core is compared against.

These are *not* the production path (that is :mod:`impact.engine.paper`); they are
standard, independent ways of integrating the same CID / PID models
(``docs/model.md``) so the study can report how the exact core compares with
what a practitioner would otherwise write:

=====================================  ==========================================================
:func:`simulate_ivp`                   event-driven, ``scipy.integrate.solve_ivp`` between
                                       impacts (RK45, DOP853, Radau, LSODA), terminal wall events,
                                       Eq. 3 at each event, sticking / merging for chatter and e = 0
:func:`simulate_rk4`                   classical RK4 with a fixed step; a step that ends beyond a
                                       wall is cut at the root of the cubic Hermite interpolant
:func:`simulate_moreau_jean`           Moreau--Jean event-capturing time stepping (theta method,
                                       velocity-level Newton law, closed-form 1-D LCP)
:func:`simulate_penalty`               compliant walls: linear spring--dashpot calibrated to e,
                                       stiff ``solve_ivp`` with contact entry / exit events
=====================================  ==========================================================

Every function has the signature
``f(system, r, t_end, t_window, start='centre', **method_settings) -> BaselineResult``
and starts from rest: x = x' = 0, damper mass at rest, centred (s = y - x = 0)
or at a wall ('left': s = -d/2, 'right': s = +d/2).

Model units (M = 1, omega = 1), state z = (x, x', y, y').  Between impacts

    x'' + 2 beta x' + x - mu rp^2 (y - x) = f sin(r t + phase) + mu a_f sgn(s')
    y''                                   = -rp^2 (y - x)       -    a_f sgn(s')

(f = force_ratio, a_f = friction_accel, rp = 0 for the CID; friction only for the
CID).  Walls at s = +-d/2, instantaneous impacts with Eq. 3 (:func:`impact_law`).

The pieces the four methods share live in :mod:`._common`; this module only
re-exports the public names.
"""

from impact.baselines._common import BaselineResult, impact_law
from impact.baselines.fixed_step import simulate_rk4
from impact.baselines.ivp import simulate_ivp
from impact.baselines.moreau import simulate_moreau_jean
from impact.baselines.penalty import simulate_penalty

METHODS = {
    "ivp": simulate_ivp,
    "rk4": simulate_rk4,
    "moreau_jean": simulate_moreau_jean,
    "penalty": simulate_penalty,
}

__all__ = [
    "BaselineResult", "impact_law", "simulate_ivp", "simulate_rk4",
    "simulate_moreau_jean", "simulate_penalty", "METHODS",
]
