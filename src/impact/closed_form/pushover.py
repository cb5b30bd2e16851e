"""The static pushover of a yielding shear building, exactly: base shear against roof drift, event to event.

A lateral load of fixed pattern f (one entry per floor) grows by a factor lam; storey i carries the shear
V_i = lam S_i, S_i the pattern's sum over the floors it carries.  With P-delta each storey resists V_i with
R_i(u) - (P_i / h_i) u, and its tangent is k - P/h elastic, b k - P/h yielding: every storey is linear between
events, so the curve is piecewise linear and each corner is found in closed form.  The roof drift D = sum u_i
is pushed monotonically; where the building's tangent turns negative (P-delta past a yielding storey's
hardening) lam falls, the storeys still on their yield surface with a positive tangent unload elastically and
the softening ones go on yielding.  The push ends at the roof drift asked, or where lam reaches 0 (gravity
alone then carries the building over: it has no lateral strength left).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from impact.model.params import G_GRAV, ParameterError

if TYPE_CHECKING:  # the command line reads PATTERNS at start, before it needs scipy's eigensolvers
    from impact.model.building import Building

PATTERNS = ("first-mode", "triangular", "uniform")


#: why a push ends: the roof reached the drift asked; the base shear fell to zero; or a softening storey would have
#: to move back while it yields (a snap-back, which no roof-displacement control can follow)
ENDS = ("roof drift reached", "no lateral strength left", "snap-back")


@dataclass
class Pushover:
    """The curve's corners: roof drift (m), base shear (N), which storeys yield from each corner on, each storey's
    drift at each corner (m; corners x storeys) and why the push ended (one of ENDS)."""

    roof_drift: np.ndarray
    base_shear: np.ndarray
    yielding: list
    storey_drift: np.ndarray
    ended: str = ENDS[0]

    def as_json(self) -> dict:
        return {"roof_drift_m": self.roof_drift.tolist(), "base_shear_N": self.base_shear.tolist(),
                "yielding_storeys": self.yielding, "storey_drift_m": self.storey_drift.tolist(),
                "ended": self.ended}


def pattern(building: Building, name: str) -> np.ndarray:
    """The load pattern per floor, normalised to sum 1: the first mode times the masses, heights times masses,
    or the masses."""
    if name not in PATTERNS:
        raise ParameterError(f"pattern = {name!r} is not allowed: choose one of {', '.join(PATTERNS)}")
    m = building.masses
    if name == "first-mode":
        f = m * np.abs(building.modes()[1][:, 0])
    elif name == "triangular":
        f = m * np.arange(1, building.storeys + 1)
    else:
        f = m.copy()
    return f / f.sum()


def _carried(f: np.ndarray) -> np.ndarray:
    return np.cumsum(f[::-1])[::-1]


def pushover(building: Building, roof_drift: float, load_pattern: str = "first-mode",
             gravity: float = G_GRAV) -> Pushover:
    """Push the roof to `roof_drift` metres; the building must be given yield drifts."""
    if building.yield_drift is None:
        raise ParameterError("pushover needs a yielding building: give yield drifts")
    if not roof_drift > 0.0:
        raise ParameterError(f"roof_drift = {roof_drift!r} is out of range: allowed > 0")
    k, dy, b = building.storey_stiffness, building.yield_drift, building.hardening
    geo = np.zeros(building.storeys)
    if building.p_delta:
        geo = _carried(building.masses) * gravity / building.storey_height
    if np.any(k - geo <= 0.0):
        raise ParameterError("P-delta outweighs a storey's elastic stiffness: the building cannot stand")
    s = _carried(pattern(building, load_pattern))
    u = np.zeros_like(k)
    p = np.zeros_like(k)  # plastic offsets
    lam = 0.0
    yielding = np.zeros(len(k), dtype=bool)
    sign = np.zeros(len(k))  # the side each yielding storey yields on
    drifts, shears, states, storey_drifts = [0.0], [0.0], [[]], [u.copy()]
    ended = ENDS[0]
    while u.sum() < roof_drift * (1 - 1e-14):
        yielding, dlam_dd, du_dd = _branches(k, b, geo, s, yielding, sign)
        if np.any(yielding & (sign * du_dd < 0)):
            ended = ENDS[2]
            break
        step = roof_drift - u.sum()
        # the next elastic storey to reach its yield surface, on either side, moving along its elastic line
        elastic = ~yielding & (du_dd != 0)
        room = np.where(du_dd > 0, p + dy - u, p - dy - u)
        to_yield = np.where(elastic, room / np.where(elastic, du_dd, 1.0), np.inf)
        step = min(step, to_yield.min(initial=np.inf))
        if dlam_dd < 0:
            step = min(step, -lam / dlam_dd)
        u, lam = u + du_dd * step, lam + dlam_dd * step
        p = np.where(yielding, u - sign * dy, p)
        hit = elastic & (to_yield <= step * (1 + 1e-12))
        sign = np.where(hit, np.sign(du_dd), sign)
        yielding = yielding | hit
        drifts.append(float(u.sum()))
        shears.append(float(lam))
        states.append([int(i) + 1 for i in np.flatnonzero(yielding)])
        storey_drifts.append(u.copy())
        if lam <= 1e-12 * max(shears):
            ended = ENDS[1]
            break
    return Pushover(np.array(drifts), np.array(shears), states, np.array(storey_drifts), ended)


def _branches(k, b, geo, s, yielding, sign):
    """Which yielding storeys keep yielding as the roof moves on, d lam / d D and each d u_i / d D.

    Assume every storey on its surface yields (on side sign); a storey with a positive tangent whose drift would
    then move back (sign * d lam < 0, its shear falling) unloads: drop it and solve again (each pass drops at least
    one).  One with a negative tangent moving back is a snap-back, which the caller ends the push on.  A perfectly plastic
    storey without P-delta (tangent 0) is a mechanism: lam stays, and the roof's drift goes into it (split evenly
    among several, which statics leaves undetermined)."""
    yielding = yielding.copy()
    while True:
        tangent = np.where(yielding, b * k - geo, k - geo)
        flat = yielding & (tangent == 0.0)
        if flat.any():
            return yielding, 0.0, flat / flat.sum()
        dlam = 1.0 / np.sum(s / tangent)
        unloading = yielding & (tangent > 0) & (sign * dlam < 0)
        if not unloading.any():
            return yielding, dlam, s * dlam / tangent
        yielding = yielding & ~unloading
