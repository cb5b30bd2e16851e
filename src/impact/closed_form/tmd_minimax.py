"""The TMD's minimax ("equal peaks") tuning and the true peak of its frequency-response curve, by numerical search.

The model and its closed forms (the response, Den Hartog's tuning) are :mod:`impact.closed_form.tmd`; these
searches are apart because they load scipy's optimisers, which the jobs that only design a TMD do not need.

Optimum.  The paper (Ref. 16) tunes the TMD by the "equal peaks" criterion:
(f, beta_t) minimise the largest peak of the frequency-response curve, and at
that minimax point the two peaks are equal.  :func:`tmd_optimum` computes that
minimax point numerically (Nelder-Mead from Den Hartog, then an exact
equal-peaks polish); it works for beta = 0 and beta > 0.

Den Hartog versus the exact minimax (beta = 0).  Den Hartog's fixed-point
theory is exact about the fixed points: every curve passes through two points
whose heights are equal for f = 1/(1 + mu), where both are sqrt(1 + 2/mu).  So
sqrt(1 + 2/mu) is a strict lower bound of the largest peak.  His damping
sqrt(3 mu / (8 (1 + mu)^3)) is the average of the two values that put a
horizontal tangent at one fixed point or the other - no single damping does
both, so the true minimax peak lies slightly *above* sqrt(1 + 2/mu) and the
true minimax (f, beta_t) differ slightly from Den Hartog's.  The exact minimax
for beta = 0 has a closed form (Nishihara & Asami, J. Vib. Acoust. 124 (2002)
576, DOI 10.1115/1.1500335), available here as :func:`nishihara_asami`; the
numerical optimum reproduces it (tests/test_tmd.py).  For mu = 0.01: f differs
from 1/(1 + mu) by 4e-7 (relative), beta_t exceeds Den Hartog's by 1.0 %, the
peak exceeds sqrt(1 + 2/mu) by 1.5e-4 (relative).

Peak versus sweep.  :func:`tmd_peak` is the true maximum of the continuous
curve on [r_min, r_max] (independent of any grid); :func:`~impact.closed_form.tmd.tmd_sweep_x_max`
is the paper's protocol (the largest amplitude on the sweep grid, r = 0.9 ... 1.1
step 0.005 in the parametric study).  The sweep value is never larger than the
peak; it is smaller when the peak falls between grid points (relative
shortfall about (curvature/2) * (distance to the nearest grid point)^2, small
for peaks broader than the step) or outside the grid's range.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, minimize, minimize_scalar

from impact.closed_form.tmd import check_ranges, den_hartog, tmd_amplitude
from impact.model.params import ParameterError, a_max

N_PEAK_GRID = 4001        # dense grid of tmd_peak on [r_min, r_max]
N_PIECE_GRID = 2001       # dense grid of each half in the equal-peaks polish
EQUAL_PEAKS_RTOL = 1e-6   # tmd_optimum refuses an optimum whose peaks differ more


def _undamped_frequencies(mu, f):
    """Natural frequencies of the undamped 2-DOF system (roots of r^4 - (1 + f^2 + mu f^2) r^2 + f^2)."""
    b = 1.0 + f * f * (1.0 + mu)
    disc = math.sqrt(max(b * b - 4.0 * f * f, 0.0))
    return math.sqrt((b - disc) / 2.0), math.sqrt((b + disc) / 2.0)


def _refined_max(mu, beta, f, beta_t, lo, hi, n, force_ratio=1.0, max_candidates=4):
    """(r, amplitude) of the largest value of |X| on [lo, hi]: dense grid + bounded Brent.

    The grid also contains the undamped natural frequencies and r = 1, r = f
    (where sharp peaks and the anti-resonance sit), so a narrow peak is
    bracketed whatever the grid step.  Each of the largest local maxima of the
    grid is refined on its bracket [r_{i-1}, r_{i+1}]; a maximum at an end of
    the interval is kept as it is (the curve's supremum is there).
    """
    extra = [x for x in (*_undamped_frequencies(mu, f), 1.0, f) if lo < x < hi]
    r = np.unique(np.concatenate([np.linspace(lo, hi, n), extra]))
    a = tmd_amplitude(r, mu, beta, f, beta_t, 1.0)
    a = np.where(np.isfinite(a), a, np.inf)
    best_i = int(np.argmax(a))
    best = (float(r[best_i]), float(a[best_i]))
    if not math.isfinite(best[1]):
        return best[0], math.inf
    interior = np.flatnonzero((a[1:-1] >= a[:-2]) & (a[1:-1] >= a[2:])) + 1
    if interior.size:
        interior = interior[np.argsort(a[interior])[::-1][:max_candidates]]

    def neg_sq(x):
        return -(tmd_amplitude(x, mu, beta, f, beta_t, 1.0) ** 2)

    for i in interior:
        res = minimize_scalar(neg_sq, bounds=(r[i - 1], r[i + 1]), method="bounded",
                              options={"xatol": 1e-13 * max(1.0, r[i])})
        cand = (float(res.x), math.sqrt(-res.fun)) if res.success else (float(r[i]), float(a[i]))
        if cand[1] > best[1]:
            best = cand
    return best[0], best[1] * force_ratio


def tmd_peak(mu, beta, f, beta_t, r_min=0.5, r_max=1.5, force_ratio=0.096):
    """(r_peak, amplitude) of the largest peak of |X| on [r_min, r_max].

    Dense grid (plus the undamped natural frequencies) then bounded Brent
    refinement of the largest local maxima, so the result is the maximum of the
    continuous curve to ~1e-12 in r, independent of any sweep grid.  The
    amplitude is in the units of ``force_ratio`` (same default as
    :func:`tmd_amplitude`); ``force_ratio=1`` gives the amplification factor.
    Compare :func:`~impact.closed_form.tmd.tmd_sweep_x_max`, the paper's grid protocol.
    """
    check_ranges(mu, beta, f, beta_t, force_ratio)
    if not (0 <= r_min < r_max):
        raise ParameterError(f"need 0 <= r_min < r_max, got r_min = {r_min!r}, r_max = {r_max!r}")
    return _refined_max(mu, beta, f, beta_t, float(r_min), float(r_max), N_PEAK_GRID, force_ratio)


def nishihara_asami(mu):
    """Exact minimax (H-infinity) tuning for an undamped structure, closed form.

    Nishihara & Asami, J. Vib. Acoust. 124 (2002) 576:
        f      = 2/(1 + mu) sqrt(2 (16 + 23 mu + 9 mu^2 + 2 (2 + mu) sqrt(4 + 3 mu)) / (3 (64 + 80 mu + 27 mu^2)))
        beta_t = 1/4 sqrt((8 + 9 mu - 4 sqrt(4 + 3 mu)) / (1 + mu))
    ``amplification`` is the largest peak of the curve at that tuning
    (computed with :func:`tmd_peak`, force_ratio = 1).
    """
    check_ranges(mu=mu, mu_positive=True)
    s = math.sqrt(4.0 + 3.0 * mu)
    f = 2.0 / (1.0 + mu) * math.sqrt(2.0 * (16.0 + 23.0 * mu + 9.0 * mu * mu + 2.0 * (2.0 + mu) * s)
                                     / (3.0 * (64.0 + 80.0 * mu + 27.0 * mu * mu)))
    beta_t = 0.25 * math.sqrt((8.0 + 9.0 * mu - 4.0 * s) / (1.0 + mu))
    _, peak = tmd_peak(mu, 0.0, f, beta_t, force_ratio=1.0)
    return {"f": f, "beta_t": beta_t, "amplification": peak}


# --------------------------------------------------------------------------
# minimax ("equal peaks") optimum
# --------------------------------------------------------------------------

def _two_peaks(mu, beta, f, beta_t, r_min, r_max):
    """Largest |X| below and above r = f (force_ratio = 1): ((r_lo, P_lo), (r_hi, P_hi)).

    r = f is the anti-resonance of the undamped TMD; the trough between the two
    peaks stays near it.  Where the two peaks are equal this split returns
    exactly the two peaks (everything between them is lower).
    """
    split = min(max(f, r_min), r_max)
    low = _refined_max(mu, beta, f, beta_t, r_min, split, N_PIECE_GRID)
    high = _refined_max(mu, beta, f, beta_t, split, r_max, N_PIECE_GRID)
    return low, high


def _max_peak(mu, beta, f, beta_t, r_min, r_max):
    return _refined_max(mu, beta, f, beta_t, r_min, r_max, N_PEAK_GRID)[1]


def _equal_peaks_f(mu, beta, beta_t, f_guess, r_min, r_max):
    """Tuning f at which the two peaks are equal, for a given beta_t (brentq)."""
    def gap(f):
        (_, p_lo), (_, p_hi) = _two_peaks(mu, beta, f, beta_t, r_min, r_max)
        return math.log(p_lo) - math.log(p_hi)

    g0 = gap(f_guess)
    for width in (1e-3, 3e-3, 1e-2, 3e-2, 1e-1):
        lo, hi = f_guess * (1 - width), f_guess * (1 + width)
        g_lo, g_hi = gap(lo), gap(hi)
        for a, ga, b, gb in ((lo, g_lo, f_guess, g0), (f_guess, g0, hi, g_hi)):
            if ga == 0.0:
                return a
            if ga * gb < 0:
                return brentq(gap, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=200)
    raise RuntimeError(f"no equal-peaks tuning near f = {f_guess} for beta_t = {beta_t}")


def tmd_optimum(mu, beta, force_ratio=0.096, *, r_min=0.5, r_max=1.5):
    """Minimax ("equal peaks") TMD tuning: (f, beta_t) minimising the largest peak.

    Stage 1: Nelder-Mead over (f, log beta_t) of the largest peak
    (:func:`tmd_peak`), started from Den Hartog.  Stage 2 (polish): at the
    minimax point of the two peaks they are equal, so the optimum is the
    minimum of the common peak height along the equal-peaks curve; for each
    beta_t the equal-peaks tuning f is solved with brentq and the common height
    is minimised over beta_t with bounded Brent.  The result is then verified:
    the two peaks agree to ``EQUAL_PEAKS_RTOL`` (else RuntimeError), and no
    small step in (f, beta_t) lowers the largest peak (``local_check``).

    Returns a dict: ``f``, ``beta_t``, ``peak_amplitude`` (largest peak, units
    of force_ratio), ``r_peaks`` and ``peaks`` (the two peaks, low/high),
    ``equal_peaks_rel_diff``, ``amplification`` (peak / force_ratio),
    ``X_m`` and ``X_m_basis``: X_m = peak / A_max with A_max =
    force_ratio/(2 beta) when beta > 0 (basis "A_max"); for beta = 0 A_max is
    infinite, so X_m = peak / force_ratio (basis "force_ratio"), ``A_max``,
    ``local_check``, ``nelder_mead_peak``, ``method``.
    """
    check_ranges(mu, beta, None, None, force_ratio, mu_positive=True)
    dh = den_hartog(mu)

    # stage 1: Nelder-Mead on the non-smooth max-peak function
    def objective(p):
        f, log_bt = p
        if f <= 0:
            return math.inf
        return _max_peak(mu, beta, f, math.exp(log_bt), r_min, r_max)

    x0 = np.array([dh["f"], math.log(dh["beta_t"])])
    nm = minimize(objective, x0, method="Nelder-Mead",
                  options={"xatol": 1e-7, "fatol": 1e-10, "maxiter": 2000,
                           "initial_simplex": [x0, x0 + [0.01 * dh["f"], 0.0], x0 + [0.0, 0.2]]})
    f_nm, bt_nm = float(nm.x[0]), math.exp(float(nm.x[1]))
    peak_nm = float(nm.fun)

    # stage 2: minimise the common height along the equal-peaks curve
    cache = {}

    def along_curve(bt):
        f_eq = _equal_peaks_f(mu, beta, bt, cache.get("f", f_nm), r_min, r_max)
        cache["f"] = f_eq
        (_, p_lo), (_, p_hi) = _two_peaks(mu, beta, f_eq, bt, r_min, r_max)
        return max(p_lo, p_hi)

    res = minimize_scalar(along_curve, bounds=(0.85 * bt_nm, 1.15 * bt_nm), method="bounded",
                          options={"xatol": 1e-10 * bt_nm})
    beta_t = float(res.x)
    f = _equal_peaks_f(mu, beta, beta_t, cache.get("f", f_nm), r_min, r_max)
    (r_lo, p_lo), (r_hi, p_hi) = _two_peaks(mu, beta, f, beta_t, r_min, r_max)
    r_peak, peak = _refined_max(mu, beta, f, beta_t, r_min, r_max, N_PEAK_GRID)
    if abs(beta_t / bt_nm - 1) > 0.149:
        raise RuntimeError(f"equal-peaks polish hit its bracket (beta_t = {beta_t}, Nelder-Mead {bt_nm})")

    # verification
    rel_diff = abs(p_lo - p_hi) / max(p_lo, p_hi)
    if rel_diff > EQUAL_PEAKS_RTOL:
        raise RuntimeError(f"optimum without equal peaks: {p_lo} vs {p_hi} (mu={mu}, beta={beta})")
    if peak > peak_nm * (1 + 1e-9):
        raise RuntimeError(f"equal-peaks polish ({peak}) is worse than Nelder-Mead ({peak_nm})")
    for r_edge in (r_lo, r_hi):
        if not (r_min < r_edge < r_max):
            raise RuntimeError(f"a peak sits at the edge of [{r_min}, {r_max}]; widen the range")
    step = 1e-4
    local = min(_max_peak(mu, beta, f * (1 + step * df), beta_t * (1 + step * db), r_min, r_max)
                for df, db in ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)))
    local_ok = local >= peak * (1 - 1e-12)

    A = a_max(beta, force_ratio)
    amplitude = peak * force_ratio
    if beta > 0:
        x_m, basis = amplitude / A, "A_max"
    else:
        x_m, basis = peak, "force_ratio (beta = 0: A_max infinite, X_m = peak / force_ratio)"
    return {
        "f": f,
        "beta_t": beta_t,
        "peak_amplitude": amplitude,
        "r_peak": r_peak,
        "r_peaks": (r_lo, r_hi),
        "peaks": (p_lo * force_ratio, p_hi * force_ratio),
        "equal_peaks_rel_diff": rel_diff,
        "amplification": peak,
        "X_m": x_m,
        "X_m_basis": basis,
        "A_max": A,
        "local_check": bool(local_ok),
        "nelder_mead_peak": peak_nm * force_ratio,
        "nelder_mead": {"f": f_nm, "beta_t": bt_nm},
        "method": ("minimax of the largest peak on [r_min, r_max]: Nelder-Mead over (f, log beta_t) "
                   "from Den Hartog, polished along the equal-peaks curve (brentq in f, bounded Brent in beta_t)"),
    }
