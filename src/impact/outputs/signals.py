"""The paper's experimental analysis chain (Sect. 3), pure numpy/scipy.

* :func:`log_decrement` -- per-cycle logarithmic decrement against amplitude
  from a free decay (Fig. 3(a), Fig. 5(a)).
* :func:`half_power` / :func:`half_power_damping` -- damping ratio from a
  frequency-response curve by the half-power method (Fig. 3(b)), refusing
  curves whose frequency grid does not resolve the peak.
* :func:`steady_amplitude` -- sqrt(2) * RMS over a window (the paper's
  amplitude of forced, possibly beating, records).
* :func:`restitution_from_drop` -- e from drop and rebound heights with the
  paper's Eq. (3b) and x'_- = 0.
* :func:`count_impacts` -- impacts from the damper's relative displacement
  (simulation) or velocity jumps in the structure's displacement (what an
  optical displacement record allows, with a stated detection limit).

Amplitudes and displacements are in whatever unit the caller passes; the
results carry the same unit.  Everything here is deterministic.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize, signal

from impact.outputs.measurements import Measurement, MeasurementError

# Assumed rms noise of the optical displacement sensor.  The paper gives only
# the sensor's range ("displacements of target up to 2 cm"), not its noise or
# sampling rate; 0.01 mm is an assumption, used by the tests and as the scale
# of the synthetic records.
ASSUMED_SENSOR_NOISE_MM = 0.01
G_GRAV = 9.80665  # m/s^2


class UnresolvedPeakError(ValueError):
    """The frequency grid does not resolve the resonance peak / half-power band."""


# ----------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------


def beta_to_delta(beta: float) -> float:
    """Log decrement of a linear oscillator with damping ratio beta: 2 pi beta / sqrt(1 - beta^2)."""
    return 2.0 * math.pi * beta / math.sqrt(1.0 - beta * beta)


def delta_to_beta(delta: float) -> float:
    """Inverse of :func:`beta_to_delta`: delta / sqrt(4 pi^2 + delta^2)."""
    return delta / math.sqrt(4.0 * math.pi**2 + delta * delta)


def _series(t: Iterable[float], x: Iterable[float], name: str = "x") -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if t.ndim != 1 or x.shape != t.shape:
        raise ValueError(f"t and {name} must be 1-D arrays of equal length (got {t.shape}, {x.shape})")
    if t.size < 3:
        raise ValueError("need at least 3 samples")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(x))):
        raise ValueError(f"t and {name} must be finite")
    if np.any(np.diff(t) <= 0):
        raise ValueError("t must be strictly increasing")
    return t, x


def _window(t: np.ndarray, t_start: float | None, t_end: float | None) -> np.ndarray:
    """Boolean mask of samples in the half-open window [t_start, t_end).

    Boundaries are compared with half a sample step of slack, so a window of
    exactly N periods on a uniform grid selects exactly N periods of samples
    regardless of floating-point rounding of the time stamps.
    """
    half = 0.5 * float(np.median(np.diff(t)))
    mask = np.ones(t.size, dtype=bool)
    if t_start is not None:
        mask &= t >= t_start - half
    if t_end is not None:
        mask &= t < t_end - half
    return mask


def _uniform_step(t: np.ndarray, rtol: float = 1e-6) -> float:
    dt = np.diff(t)
    step = float(np.median(dt))
    if np.max(np.abs(dt - step)) > rtol * step + 1e-12 * max(1.0, abs(t[-1])):
        raise ValueError("this analysis needs uniformly sampled t")
    return step


def dominant_frequency(t: Sequence[float], x: Sequence[float]) -> float:
    """Frequency [1/time unit of t] of the largest spectral peak of x (mean removed).

    Linear trend removed, Hann window, zero-padded FFT, parabolic
    interpolation of the log-magnitude peak; a starting value, not a
    precision estimate.
    """
    t, x = _series(t, x)
    dt = float(np.median(np.diff(t)))
    y = signal.detrend(x) * np.hanning(x.size)
    nfft = 1 << int(math.ceil(math.log2(8 * x.size)))
    spec = np.abs(np.fft.rfft(y, nfft))
    spec[0] = 0.0
    k = int(np.argmax(spec))
    if 0 < k < spec.size - 1 and spec[k - 1] > 0 and spec[k + 1] > 0:
        a, b, c = np.log(spec[k - 1 : k + 2])
        den = a - 2 * b + c
        shift = 0.5 * (a - c) / den if den != 0 else 0.0
    else:
        shift = 0.0
    return (k + shift) / (nfft * dt)


# ----------------------------------------------------------------------------
# log decrement
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class LogDecrement:
    """Log decrement of a free decay, per cycle against amplitude.

    Per pair of consecutive windows k, k+1: ``delta`` the log decrement per
    cycle, ``amplitude`` the geometric mean of the two window amplitudes (same
    unit as the input x), ``t`` the midpoint of the two window centres,
    ``frequency`` the damped frequency (1/time unit of t).  ``mean`` is the
    average delta over the pairs, ``std`` their standard deviation (the
    per-cycle scatter).  Per window: ``window_t`` (centre), ``window_amplitude``
    (envelope amplitude at the centre) and ``window_rms_residual``, the rms
    misfit of the local damped-sinusoid model -- compare it with the sensor
    noise: much larger means the cycle is not locally a damped sinusoid
    (impacts, beating, clipping).
    """

    t: np.ndarray
    amplitude: np.ndarray
    delta: np.ndarray
    frequency: np.ndarray
    mean: float
    std: float
    cycles: int
    window_t: np.ndarray
    window_amplitude: np.ndarray
    window_rms_residual: np.ndarray


def upward_crossings(t: np.ndarray, y: np.ndarray, hysteresis: float = 0.0) -> np.ndarray:
    """Times where y crosses zero upwards, each after y was below -hysteresis.

    The crossing time is linearly interpolated between the two samples.
    """
    idx = np.flatnonzero((y[:-1] <= 0.0) & (y[1:] > 0.0))
    out = []
    last = -1
    for i in idx:
        if hysteresis > 0.0 and np.min(y[last + 1 : i + 1]) >= -hysteresis:
            continue  # never went properly negative since the last crossing: noise chatter
        frac = -y[i] / (y[i + 1] - y[i])
        out.append(t[i] + frac * (t[i + 1] - t[i]))
        last = i
    return np.array(out)


def _fit_damped_sine(tau: np.ndarray, x: np.ndarray, omega0: float) -> tuple[np.ndarray, float]:
    """Least-squares fit x = exp(-s tau) (a cos w tau + b sin w tau) + c.

    Returns ([s, w, a, b, c], rms residual).
    """
    basis = np.column_stack([np.cos(omega0 * tau), np.sin(omega0 * tau), np.ones_like(tau)])
    (a, b, c), *_ = np.linalg.lstsq(basis, x, rcond=None)
    p0 = np.array([0.0, omega0, a, b, c])

    def resid(p):
        s, w, a, b, c = p
        env = np.exp(-s * tau)
        return env * (a * np.cos(w * tau) + b * np.sin(w * tau)) + c - x

    def jac(p):
        s, w, a, b, c = p
        env = np.exp(-s * tau)
        cw, sw = np.cos(w * tau), np.sin(w * tau)
        osc = a * cw + b * sw
        return np.column_stack([-tau * env * osc, env * tau * (-a * sw + b * cw), env * cw, env * sw,
                                np.ones_like(tau)])

    sol = optimize.least_squares(resid, p0, jac=jac, method="lm", x_scale="jac",
                                 xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=200)
    return sol.x, float(np.sqrt(np.mean(sol.fun**2)))


def log_decrement(t: Sequence[float], x: Sequence[float], *, cycles: int = 1,
                  t_start: float | None = None, t_end: float | None = None,
                  min_amplitude: float | None = None, lowpass: bool = True) -> LogDecrement:
    """Logarithmic decrement per cycle against amplitude, from a free decay.

    1. Cycles: upward zero crossings of a zero-phase low-passed copy of the
       signal (Butterworth, cut-off 3x the dominant frequency, median removed);
       a crossing counts only after the signal went below minus three noise
       rms, so sensor noise cannot create false cycles.  The record is cut into
       consecutive windows of ``cycles`` cycles.
    2. Amplitude per window: the *raw* samples of the window are fitted by
       least squares with a locally damped sinusoid plus offset,
       ``exp(-s tau) (a cos w tau + b sin w tau) + c`` (tau from the window
       centre t_k); A_k = sqrt(a^2 + b^2) is the envelope at t_k.  Every sample
       of the cycle contributes (a peak picked from single samples would carry
       the full sensor noise), the offset c absorbs the sensor's zero, and the
       frequency comes with it.
    3. Per consecutive pair: delta = (ln(A_k / A_{k+1}) / (t_{k+1} - t_k)) * T,
       T = 2 pi / w the local damped period -- the classical
       ln(x_n / x_{n+1}) per cycle, on fitted instead of sampled peaks.

    For an exactly linear viscous decay every step is exact, so delta =
    2 pi beta / sqrt(1 - beta^2) to solver precision.  With a nonlinear damper
    (impacts) delta is the equivalent per-cycle decrement at that amplitude,
    as read from peaks in the paper.  Pairs whose amplitude is below
    ``min_amplitude`` are dropped (the paper plots no points below 1 cm
    double amplitude).
    """
    t, x = _series(t, x)
    if cycles < 1:
        raise ValueError("cycles must be >= 1")
    mask = _window(t, t_start, t_end)
    t, x = t[mask], x[mask]
    if t.size < 8:
        raise ValueError("too few samples in the window")
    fs = 1.0 / float(np.median(np.diff(t)))
    f0 = dominant_frequency(t, x)
    y = x - np.median(x)
    noise = 0.0
    if lowpass and 3.0 * f0 < 0.45 * fs and x.size > 30:
        sos = signal.butter(4, 3.0 * f0, fs=fs, output="sos")
        ys = signal.sosfiltfilt(sos, y)
        noise = float(np.std(y - ys))
        y = ys
    z = upward_crossings(t, y, hysteresis=3.0 * noise)
    if z.size < 2 * cycles + 1:
        raise ValueError(f"found {max(z.size - 1, 0)} full cycles, need at least {2 * cycles} "
                         f"(two windows of {cycles})")
    win = []
    for k in range(0, z.size - cycles, cycles):
        lo, hi = z[k], z[k + cycles]
        sel = (t >= lo) & (t <= hi)
        if np.count_nonzero(sel) < 6:
            raise ValueError("fewer than 6 samples per window: sampling too slow for this signal")
        tc = 0.5 * (lo + hi)
        omega0 = 2.0 * math.pi * cycles / (hi - lo)
        (_s, w, a, b, _c), rms = _fit_damped_sine(t[sel] - tc, x[sel], omega0)
        win.append((tc, math.hypot(a, b), w, rms))
    wt, wa, ww, wr = (np.array(col) for col in zip(*win))
    amp = np.sqrt(wa[:-1] * wa[1:])
    omega = 0.5 * (ww[:-1] + ww[1:])
    delta = np.log(wa[:-1] / wa[1:]) / np.diff(wt) * (2.0 * math.pi / omega)
    keep = np.ones(delta.size, dtype=bool) if min_amplitude is None else amp >= min_amplitude
    if not np.any(keep):
        raise ValueError("no cycle above min_amplitude")
    d = delta[keep]
    return LogDecrement(t=(0.5 * (wt[:-1] + wt[1:]))[keep], amplitude=amp[keep], delta=d,
                        frequency=(omega / (2.0 * math.pi))[keep], mean=float(np.mean(d)),
                        std=float(np.std(d, ddof=1)) if d.size > 1 else 0.0, cycles=cycles,
                        window_t=wt, window_amplitude=wa, window_rms_residual=wr)


# ----------------------------------------------------------------------------
# half-power method
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class HalfPower:
    """Result of :func:`half_power`.

    ``beta`` = (r2 - r1) / (2 r_peak); ``r1``, ``r2`` the half-power points;
    ``bracket_ratio`` the amplitude (relative to the peak) of the first sample
    below the half-power level, on the worse side -- close to 1/sqrt(2) means
    the crossing was measured, close to 0 means it was guessed by the
    interpolant; ``step_over_bandwidth`` the grid step next to the peak over
    the half-power bandwidth r2 - r1; ``resolved`` whether the grid resolves
    the band (see :func:`half_power`).
    """

    beta: float
    r_peak: float
    amplitude_peak: float
    r1: float
    r2: float
    bracket_ratio: float
    step_over_bandwidth: float
    samples_in_band: int
    resolved: bool
    method: str


class _Quad:
    """Quadratic q(u) through three points, held in a centred, scaled variable (well conditioned)."""

    def __init__(self, u: np.ndarray, q: np.ndarray):
        self.uc = float(np.mean(u))
        self.us = float(np.ptp(u)) or 1.0
        self.c = np.polyfit((u - self.uc) / self.us, q, 2)

    @property
    def convex(self) -> bool:
        return self.c[0] > 0

    def vertex(self) -> tuple[float, float]:
        v = -self.c[1] / (2.0 * self.c[0])
        return self.uc + self.us * v, float(np.polyval(self.c, v))

    def roots(self, level: float) -> np.ndarray:
        """Real roots u of q(u) = level, sorted."""
        c = self.c.copy()
        c[-1] -= level
        rts = np.roots(c)
        rts = rts[np.abs(rts.imag) <= 1e-12 * np.maximum(1.0, np.abs(rts.real))].real
        return np.sort(self.uc + self.us * rts)

    def root_in(self, level: float, lo: float, hi: float) -> float | None:
        a, b = min(lo, hi), max(lo, hi)
        tol = 1e-12 * max(1.0, b - a)
        good = [v for v in self.roots(level) if a - tol <= v <= b + tol]
        return None if not good else min(max(good[0], a), b)


def half_power(r: Sequence[float], amplitude: Sequence[float], *, method: str = "local",
               min_bracket_ratio: float = 0.3, strict: bool = True) -> HalfPower:
    """Damping ratio from a frequency-response curve by the half-power method.

    ``r`` are frequency ratios (or frequencies: beta is dimensionless either
    way), ``amplitude`` the steady amplitudes.  Steps:

    1. the largest sample k; its neighbours must exist (peak not at the edge);
    2. peak: ``method="local"`` fits a quadratic in u = r^2 to q = 1/A^2
       through samples k-1, k, k+1 and takes its vertex (for a linear
       single-degree-of-freedom system q is exactly quadratic in r^2, so the
       peak between samples is recovered); ``method="linear"`` takes the
       largest sample as the peak, as one reads it off a plot;
    3. half-power level A_peak / sqrt(2); on each side, the first sample below
       it brackets the half-power point with its inner neighbour, and the
       crossing is found by the same local quadratic of 1/A^2 through the
       bracketing pair and the next sample inwards (``linear``: straight line
       in A between the pair);
    4. beta = (r2 - r1) / (2 r_peak).

    Resolution check.  The band is *resolved* when (local method) the peak
    quadratic has its minimum between its samples, at least one sample lies at
    or above the half-power level, and the samples bracketing both half-power
    points have at least ``min_bracket_ratio`` of the peak amplitude (for an
    SDOF curve, ratio 0.3 means a sample within about 3.2 beta of the peak).
    Otherwise the half-power points lie in a grid interval much wider than the
    band itself, so their location comes from the interpolant and not from
    the data: with ``strict`` (default) :class:`UnresolvedPeakError` is
    raised, naming the step and the bandwidth; with ``strict=False`` the
    estimate is returned with ``resolved=False``.
    """
    if method not in ("local", "linear"):
        raise ValueError("method must be 'local' or 'linear'")
    r = np.asarray(r, dtype=float)
    amp = np.asarray(amplitude, dtype=float)
    if r.ndim != 1 or amp.shape != r.shape:
        raise ValueError("r and amplitude must be 1-D arrays of equal length")
    if r.size < 5:
        raise ValueError("need at least 5 points of the frequency-response curve")
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(amp)) and np.all(amp > 0)):
        raise ValueError("r must be finite and amplitudes finite and > 0")
    order = np.argsort(r, kind="stable")
    r, amp = r[order], amp[order]
    if np.any(np.diff(r) <= 0):
        raise ValueError("r values must be distinct")
    n = r.size
    k = int(np.argmax(amp))
    if k == 0 or k == n - 1:
        raise UnresolvedPeakError(f"the peak is at the edge of the sweep (r = {r[k]:g}); "
                                  "extend the sweep beyond the resonance")
    q = 1.0 / amp**2
    u = r**2
    # the peak
    peak_quad = None
    r_peak, a_peak = float(r[k]), float(amp[k])
    if method == "local":
        quad = _Quad(u[k - 1 : k + 2], q[k - 1 : k + 2])
        if quad.convex:
            u0, q0 = quad.vertex()
            if u[k - 1] <= u0 <= u[k + 1] and 0.0 < q0 <= q[k]:
                r_peak, a_peak = math.sqrt(u0), 1.0 / math.sqrt(q0)
                peak_quad = quad
        # else: 1/A^2 through the top three samples has no sensible minimum
        # (e.g. two near-equal samples straddling a peak much sharper than the
        # grid, plus noise): the peak is not resolved
    level = a_peak / math.sqrt(2.0)
    q_level = 1.0 / level**2
    in_band = int(np.count_nonzero(amp >= level))
    crossings = []
    ratios = []
    if amp[k] < level:
        # no sample at or above the half-power level: the whole band lies
        # between two samples and only the peak quadratic can place it
        roots = peak_quad.roots(q_level)
        crossings = [math.sqrt(max(roots[0], 0.0)), math.sqrt(max(roots[-1], 0.0))]
        ratios = [float(amp[k] / a_peak)]
    else:
        for side in (-1, 1):
            j = k
            while 0 <= j < n and amp[j] >= level:
                j += side
            if not 0 <= j < n:
                where = "low" if side < 0 else "high"
                raise UnresolvedPeakError(f"the amplitude does not fall to the half-power level on the "
                                          f"{where} side within the sweep; extend the sweep")
            i = j - side  # inner sample of the bracket, at or above the level (may be k itself)
            ratios.append(float(amp[j] / a_peak))
            if method == "linear":
                rc = float(r[i] + (level - amp[i]) * (r[j] - r[i]) / (amp[j] - amp[i]))
            else:
                rc = None
                idx = [i - side, i, j]
                if 0 <= min(idx) and max(idx) < n:
                    uc = _Quad(u[idx], q[idx]).root_in(q_level, u[i], u[j])
                    if uc is not None:
                        rc = math.sqrt(uc)
                if rc is None:  # noisy data: the quadratic misses the bracket; a line in 1/A^2
                    rc = math.sqrt(u[i] + (q_level - q[i]) * (u[j] - u[i]) / (q[j] - q[i]))
            crossings.append(float(rc))
    r1, r2 = crossings
    bw = r2 - r1
    beta = bw / (2.0 * r_peak)
    step = float(max(r[k] - r[k - 1], r[k + 1] - r[k]))
    step_over_bw = step / bw if bw > 0 and math.isfinite(bw) else math.inf
    bracket = min(ratios)
    peak_ok = method == "linear" or peak_quad is not None
    resolved = bool(peak_ok and amp[k] >= level and bracket >= min_bracket_ratio
                    and math.isfinite(beta) and beta > 0)
    if strict and not peak_ok:
        raise UnresolvedPeakError(
            f"the frequency grid does not resolve the peak: 1/A^2 through the three highest samples "
            f"(r = {r[k - 1]:g}, {r[k]:g}, {r[k + 1]:g}) has no minimum between them; the peak is sharper "
            f"than the grid step {step:.3g} (or the curve is too noisy); refine the sweep near the peak")
    if strict and not resolved:
        if amp[k] < level:
            why = (f"no sample reaches the half-power level (the highest is at {amp[k] / a_peak:.3f} of "
                   f"the interpolated peak): the whole band lies between two samples")
        else:
            why = (f"the first sample below the half-power level is at {bracket:.3f} of the peak "
                   f"(needs >= {min_bracket_ratio:g})")
        raise UnresolvedPeakError(
            f"the frequency grid does not resolve the half-power band: grid step near the peak "
            f"{step:.3g} vs estimated half-power bandwidth {bw:.3g} ({step_over_bw:.1f}x); {why}; "
            f"the half-power points are then set by the interpolant, not by data. Sample the peak "
            f"with a step <= about half the bandwidth (~{0.5 * bw:.2g} here), or pass strict=False "
            f"to get the unresolved estimate (beta = {beta:.3g})")
    return HalfPower(beta=float(beta), r_peak=float(r_peak), amplitude_peak=float(a_peak), r1=r1, r2=r2,
                     bracket_ratio=bracket, step_over_bandwidth=step_over_bw, samples_in_band=in_band,
                     resolved=resolved, method=method)


def half_power_damping(r: Sequence[float], amplitude: Sequence[float], **kwargs) -> float:
    """beta = (r2 - r1) / (2 r_peak); see :func:`half_power` for the method and its checks."""
    return half_power(r, amplitude, **kwargs).beta


# ----------------------------------------------------------------------------
# steady amplitude
# ----------------------------------------------------------------------------


def steady_amplitude(t: Sequence[float], x: Sequence[float], t_start: float | None = None,
                     t_end: float | None = None, *, remove_mean: bool = True) -> float:
    """sqrt(2) * RMS of x over the half-open window [t_start, t_end).

    The paper's amplitude of a forced record (Sect. 3(2)): equal to the
    amplitude of a sinusoid, and a consistent measure for beating records.
    For a sinusoid it is exact when the window spans whole periods of
    uniformly spaced samples (end sample excluded: the half-open window).
    ``remove_mean`` subtracts the window mean first (a sensor offset would
    otherwise inflate the RMS); the simulation protocol does not detrend, which
    makes no difference for a response symmetric about zero.  Non-uniform
    sampling is handled by trapezoidal time averaging.
    """
    t, x = _series(t, x)
    mask = _window(t, t_start, t_end)
    tw, xw = t[mask], x[mask]
    if tw.size < 2:
        raise ValueError("fewer than 2 samples in the window")
    dt = np.diff(tw)
    uniform = np.max(np.abs(dt - dt.mean())) <= 1e-6 * dt.mean()
    if uniform:
        mean = xw.mean() if remove_mean else 0.0
        ms = np.mean((xw - mean) ** 2)
    else:
        span = tw[-1] - tw[0]
        mean = np.trapezoid(xw, tw) / span if remove_mean else 0.0
        ms = np.trapezoid((xw - mean) ** 2, tw) / span
    return float(math.sqrt(2.0 * ms))


def whole_periods(t_start: float, t_end: float, period: float) -> tuple[float, float]:
    """(t_start, t_end') with t_end' - t_start the largest whole number of periods."""
    n = math.floor((t_end - t_start) / period + 1e-9)
    if n < 1:
        raise ValueError("window shorter than one period")
    return t_start, t_start + n * period


# ----------------------------------------------------------------------------
# restitution from drop tests
# ----------------------------------------------------------------------------


def restitution_from_drop(h_drop, h_rebound, mu_ball_over_target):
    """Coefficient of restitution from drop tests, the paper's Eq. (3b) with x'_- = 0.

    Eq. (3b): y'_+ = (1 + e)/(1 + mu) x'_- + (mu - e)/(1 + mu) y'_-.  With the
    struck body at rest before impact (x'_- = 0), the ball arriving at speed
    v_d = sqrt(2 g h_drop) and leaving at v_r = sqrt(2 g h_rebound) in the
    opposite direction, y'_+ / y'_- = -v_r / v_d = (mu - e)/(1 + mu), so

        e = mu + (1 + mu) sqrt(h_rebound / h_drop).

    Eq. (3a) gives the struck body x'_+ = mu (1 + e)/(1 + mu) y'_-, and indeed
    the relative velocity is reversed with factor e.  ``mu`` = m_ball /
    m_target; with mu = 0 (immobile target) this is e = sqrt(h_r / h_d).  The
    paper uses the ball-to-structure ratio mu (0.54 ... 2.52 %), although it
    also says the structure was "stationary before and after the impact",
    which would mean mu = 0; the two readings differ by mu (1 + sqrt(h_r/h_d)),
    i.e. 0.007 ... 0.034 for the paper's balls.  Air drag and the ball's
    rotation are neglected.  Heights in any common unit.  Returns an array
    (a float for scalar input).  Raises ValueError if a row implies e > 1.
    """
    hd = np.asarray(h_drop, dtype=float)
    hr = np.asarray(h_rebound, dtype=float)
    mu = np.asarray(mu_ball_over_target, dtype=float)
    if np.any(~np.isfinite(hd)) or np.any(hd <= 0):
        raise ValueError("h_drop must be finite and > 0")
    if np.any(~np.isfinite(hr)) or np.any(hr < 0):
        raise ValueError("h_rebound must be finite and >= 0")
    if np.any(~np.isfinite(mu)) or np.any(mu < 0):
        raise ValueError("mu_ball_over_target must be finite and >= 0")
    e = mu + (1.0 + mu) * np.sqrt(hr / hd)
    bad = np.flatnonzero(np.atleast_1d(e) > 1.0 + 1e-12)
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"drop {i + 1}: rebound too high for Eq. (3b): e = {np.atleast_1d(e)[i]:.4g} > 1")
    return float(e) if e.ndim == 0 else e


def rebound_height(h_drop, e, mu_ball_over_target):
    """Rebound height predicted by Eq. (3b) with x'_- = 0 (the inverse of :func:`restitution_from_drop`).

    h_rebound = h_drop ((e - mu)/(1 + mu))^2; requires e >= mu (otherwise the
    ball would follow the struck body instead of rebounding).
    """
    hd = np.asarray(h_drop, dtype=float)
    e = np.asarray(e, dtype=float)
    mu = np.asarray(mu_ball_over_target, dtype=float)
    if np.any(e < mu) or np.any(e > 1):
        raise ValueError("need mu <= e <= 1")
    out = hd * ((e - mu) / (1.0 + mu)) ** 2
    return float(out) if out.ndim == 0 else out


# ----------------------------------------------------------------------------
# impact counting
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class ImpactCount:
    """Impacts found in a record.

    ``times`` of the impacts; ``signal`` which signal was used
    ("relative_displacement" or "structure_displacement"); ``wall`` the sign of
    the wall hit (+1 / -1) for the relative displacement, the sign of the
    velocity jump for the structure displacement; ``min_detectable_jump`` the
    smallest velocity jump of the structure detectable at the threshold (units
    of x per time unit of t; None for the relative displacement, where every
    contact is seen); ``noise_rms`` the noise level used.
    """

    times: np.ndarray
    wall: np.ndarray
    signal: str
    min_detectable_jump: float | None = None
    noise_rms: float | None = None

    @property
    def count(self) -> int:
        return int(self.times.size)


def _contacts_from_relative(t: np.ndarray, s: np.ndarray, d: float, atol: float) -> ImpactCount:
    half = 0.5 * d
    ds = np.diff(s)
    sgn = np.sign(ds)
    nz = np.flatnonzero(sgn != 0)
    times, walls = [], []
    if nz.size >= 2:
        change = np.flatnonzero(sgn[nz[:-1]] != sgn[nz[1:]])
        for c in change:
            a, b = nz[c], nz[c + 1]
            kext = a + 1  # extremum sample (first of a plateau, if s rests at the wall)
            going_up = sgn[a] > 0
            wall = 1.0 if going_up else -1.0
            tol = max(abs(ds[a]), abs(ds[b])) + atol
            if wall * s[kext] >= half - tol:
                times.append(t[kext])
                walls.append(wall)
    return ImpactCount(np.array(times), np.array(walls), "relative_displacement")


def kink_filter(n_half: int, degree: int, dt: float) -> np.ndarray:
    """FIR weights estimating a velocity jump at the centre of a (2 n_half + 1)-sample window.

    Least squares of the window with a polynomial of ``degree`` in tau plus a
    ramp max(tau, 0): the ramp's coefficient is the jump in slope.  For an even
    degree the smooth motion biases the estimate only through its terms of
    order degree + 2 and higher.
    """
    tau = np.arange(-n_half, n_half + 1) * dt
    cols = [tau**p for p in range(degree + 1)] + [np.maximum(tau, 0.0)]
    return np.linalg.pinv(np.column_stack(cols))[-1]


def _noise_from_differences(x: np.ndarray) -> float:
    """Robust white-noise rms from 4th differences (the smooth motion is ~ (omega dt)^4 smaller)."""
    d4 = np.diff(x, 4)
    mad = np.median(np.abs(d4 - np.median(d4)))
    return float(1.4826 * mad / math.sqrt(70.0))


def count_impacts(t: Sequence[float], *, s: Sequence[float] | None = None, d: float | None = None,
                  x: Sequence[float] | None = None, noise_rms: float | None = None,
                  window: float | None = None, degree: int = 4, threshold: float = 6.0,
                  atol: float | None = None) -> ImpactCount:
    """Count impacts in a record; give exactly one of ``s`` (with ``d``) or ``x``.

    ``s`` -- the damper's displacement relative to the structure, y - x, and
    ``d`` the total clearance (same unit).  An impact is a reversal of s at a
    wall: a local extremum (or the start of a rest at the wall) within one
    sample step (+ ``atol``) of +-d/2.  Exact for a sampled simulation; the
    paper's rig had no sensor for it (impacts were marked by eye and ear on the
    pen record).  A sticking phase (ball resting on a wall) counts as one
    impact; the Zeno sequence of micro-impacts that precedes it is not
    resolved.

    ``x`` -- the structure's displacement alone, e.g. the optical sensor.  An
    impact makes a jump of the structure's velocity,
    mu (1 + e)/(1 + mu) * (relative approach speed), i.e. a kink in x.  Each
    sample is tested for a kink with a matched least-squares filter
    (:func:`kink_filter`: polynomial of ``degree`` plus a ramp over
    +-``window``, default 1/8 of the dominant period); a kink is reported
    where the estimated jump exceeds ``threshold`` times its noise standard
    error (non-maximum suppression over the window).  ``noise_rms`` is the
    sensor's white-noise rms (estimated from 4th differences if not given).
    Limits: jumps below ``min_detectable_jump`` (returned) are missed -- for
    the paper's light balls (mu = 0.54 %) and slow approach this is most
    impacts; two impacts closer than the window merge; the wall cannot be
    told, only the sign of the jump; the sensor's own bandwidth/smoothing (not
    modelled) lowers the sensitivity further.  Needs uniform sampling.
    """
    t = np.asarray(t, dtype=float)
    if (s is None) == (x is None):
        raise ValueError("give exactly one of s (relative displacement, with d) or x (structure displacement)")
    if s is not None:
        t, s = _series(t, s, "s")
        if d is None or not d > 0:
            raise ValueError("d (total clearance, > 0) is needed with s")
        return _contacts_from_relative(t, s, float(d), 1e-9 * d if atol is None else float(atol))
    t, x = _series(t, x)
    dt = _uniform_step(t)
    if window is None:
        window = 1.0 / (8.0 * dominant_frequency(t, x))
    n_half = max(int(round(window / dt)), degree + 1)
    if 2 * n_half + 1 > x.size:
        raise ValueError("record shorter than the detection window")
    h = kink_filter(n_half, degree, dt)
    sigma = _noise_from_differences(x) if noise_rms is None else float(noise_rms)
    if not sigma > 0:
        raise ValueError("noise_rms must be > 0 (a noise-free record: pass a small positive value)")
    se = sigma * float(np.linalg.norm(h))
    jump = np.correlate(x, h, mode="valid")  # jump[i] belongs to sample i + n_half
    z = np.abs(jump) / se
    peaks, _ = signal.find_peaks(z, height=threshold, distance=n_half + 1)
    idx = peaks + n_half
    return ImpactCount(times=t[idx], wall=np.sign(jump[peaks]), signal="structure_displacement",
                       min_detectable_jump=threshold * se, noise_rms=sigma)


def impacts_per_cycle(times: Sequence[float], forcing_frequency: float, t_start: float, t_end: float) -> float:
    """AIPC: impacts in [t_start, t_end) divided by the forcing cycles in the window."""
    times = np.asarray(times, dtype=float)
    n = np.count_nonzero((times >= t_start) & (times < t_end))
    return float(n / ((t_end - t_start) * forcing_frequency))


# ----------------------------------------------------------------------------
# record-level chain
# ----------------------------------------------------------------------------


def free_decay_delta(record: Measurement, **kwargs) -> LogDecrement:
    """:func:`log_decrement` of a ``free_decay`` record, amplitudes in mm."""
    if record.kind != "free_decay":
        raise MeasurementError(f"{record.path}: kind {record.kind} is not free_decay")
    return log_decrement(record.t, record.x_in("mm"), **kwargs)


def drop_test_restitution(record: Measurement) -> np.ndarray:
    """e of every drop in a ``drop_test`` record, Eq. (3b) with the header's mu."""
    if record.kind != "drop_test":
        raise MeasurementError(f"{record.path}: kind {record.kind} is not drop_test")
    try:
        return np.atleast_1d(restitution_from_drop(record.drop_height_cm, record.rebound_height_cm,
                                                   record.header["mu"]))
    except ValueError as exc:
        raise MeasurementError(f"{record.path}: {exc}") from None


@dataclass(frozen=True)
class SweepCurve:
    """A frequency-response curve: frequency ratios and sqrt(2)*RMS amplitudes [mm], sorted by r."""

    r: np.ndarray
    amplitude: np.ndarray


def sweep_curve(records: Iterable[Measurement], *, t_start: float | None = None, t_end: float | None = None,
                structure_hz: float | None = None) -> SweepCurve:
    """Amplitude (mm) against r from ``forced_sweep_point`` records.

    Each record's amplitude is :func:`steady_amplitude` over [t_start, t_end)
    (default: the whole record), trimmed to whole forcing periods when the
    forcing frequency is known (header ``forcing_hz``, or ``r`` times the
    header's or the given ``structure_hz``).  Beating records are averaged
    over whatever beats the window holds, as in the paper.
    """
    rs, amps = [], []
    for rec in records:
        if rec.kind != "forced_sweep_point":
            raise MeasurementError(f"{rec.path}: kind {rec.kind} is not forced_sweep_point")
        t = rec.t
        lo = t[0] if t_start is None else t_start
        hi = t[-1] + float(np.median(np.diff(t))) if t_end is None else t_end
        fhz = rec.header.get("forcing_hz")
        shz = rec.header.get("structure_hz", structure_hz)
        if fhz is None and shz is not None:
            fhz = rec.header["r"] * shz
        if fhz is not None:
            lo, hi = whole_periods(lo, hi, 1.0 / fhz)
        rs.append(rec.header["r"])
        amps.append(steady_amplitude(t, rec.x_in("mm"), lo, hi))
    if not rs:
        raise ValueError("no records")
    order = np.argsort(rs)
    return SweepCurve(np.asarray(rs)[order], np.asarray(amps)[order])
