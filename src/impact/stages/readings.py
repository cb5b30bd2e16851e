"""Two more readings of a sweep's X_m beside the simulated grid maximum.

The closed-form reading.  The paper says Masri's closed form "is utilized" where the two-impacts-per-
cycle (2-EIPC) orbit exists, because its simulations were unreliable at the limits of that range.  If
it took x_max from the closed form there, its CID e-trend would follow the closed form.  At each grid
frequency the stable, admissible 2-EIPC orbit (:func:`impact.closed_form.masri.masri_2eipc`) is measured as the
protocol measures a simulation: sqrt(2) times the RMS of x over the protocol's window, in the run's
own time (the force F sin(r t + phase) fixes where the window falls on the orbit).  So where a run
from rest has settled on that orbit, the two readings are the same number, not merely close.

The refined peak.  X_m is the maximum over a frequency grid (dr = 0.005): a sharp resonance peak
falls between grid points.  Each local maximum of the grid within 5 % of the largest is refined by a
bounded Brent search between its neighbours; every candidate is a full protocol run from rest, so the
refined value is the same measure as the grid's, taken at more frequencies.  It is never below the
grid's, since the grid's own points are candidates.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar

from impact.closed_form.masri import BRANCHES, forced_flow, masri_2eipc
from impact.engine.run import simulate_system as simulate
from impact.model.kinds import is_free_mass
from impact.model.params import Protocol, System

R_TOL = 1e-7       # refinement tolerance in r: a smooth peak's value to (R_TOL/beta)^2/2 ~ 2e-10 at beta = 0.0048
MAX_RUNS = 60      # protocol runs per refined bracket at most
NEAR_PEAK = 0.95   # local maxima within 5 % of the grid's largest are refined too
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)
_PIECES = 64       # Gauss-Legendre pieces per half period: x^2 is smooth between impacts


def _flight_integral(root: dict, beta: float, r: float, force_ratio: float, upto: float) -> float:
    """Integral of x^2 from a +d/2 impact of the orbit (orbit time 0) to orbit time ``upto`` <= pi/r."""
    if upto <= 0.0:
        return 0.0
    pieces = max(1, math.ceil(_PIECES * upto * r / math.pi))
    edges = np.linspace(0.0, upto, pieces + 1)
    mid, half = 0.5 * (edges[1:] + edges[:-1]), 0.5 * np.diff(edges)
    t = (mid[:, None] + half[:, None] * _GL_X[None, :]).ravel()
    x = forced_flow(0.0, float(root["x0"]), float(root["v_plus"]), t, beta, r, force_ratio,
                    float(root["force_phase"]))[0]
    return float(np.sum(np.repeat(half, _GL_X.size) * np.tile(_GL_W, edges.size - 1) * x * x))


def orbit_window_amplitude(root: dict, beta: float, r: float, force_ratio: float, phase: float,
                           t0: float, t1: float) -> float:
    """sqrt(2) RMS of the 2-EIPC orbit's x over [t0, t1] of a run whose force is F sin(r t + phase).

    The orbit is antisymmetric (x(s + T) = -x(s), T = pi/r), so x^2 has period T; orbit time s
    and run time t meet where the forces agree, s = t + (phase - force_phase)/r.
    """
    half_period = math.pi / r
    whole = _flight_integral(root, beta, r, force_ratio, half_period)
    shift = (phase - float(root["force_phase"])) / r

    def integral_to(t):
        periods, rest = divmod(t + shift, half_period)
        return periods * whole + _flight_integral(root, beta, r, force_ratio, rest)

    return math.sqrt(2.0 * (integral_to(t1) - integral_to(t0)) / (t1 - t0))


def closed_form_amplitude(system: System, r: float, protocol: Protocol) -> float:
    """The protocol's amplitude of the stable, admissible 2-EIPC orbit at r (the largest, if both
    roots are); NaN where there is none.  Frictionless CID only: the closed form knows no friction."""
    if not is_free_mass(system.kind) or system.nu != 0.0:
        raise ValueError("the 2-EIPC closed form is the frictionless CID's (a free mass between walls, nu = 0)")
    sol = masri_2eipc(system.mu, system.e, system.beta, r, system.gap, system.force_ratio)
    amplitudes = [orbit_window_amplitude(sol[b], system.beta, r, system.force_ratio, system.phase,
                                         protocol.t_window, protocol.t_end)
                  for b in BRANCHES if sol[b]["admissible"] and sol[b]["stable"]]
    return max(amplitudes, default=math.nan)


def closed_form_sweep(system: System, r_values, protocol: Protocol) -> np.ndarray:
    return np.array([closed_form_amplitude(system, float(r), protocol) for r in r_values])


def _brackets(r: np.ndarray, amp: np.ndarray) -> list[tuple[float, float]]:
    """(lo, hi) around each local maximum of the grid within NEAR_PEAK of its largest value."""
    best = np.nanmax(amp)
    out = []
    for i in range(r.size):
        left = amp[i - 1] if i > 0 else -np.inf
        right = amp[i + 1] if i + 1 < r.size else -np.inf
        if amp[i] >= NEAR_PEAK * best and amp[i] >= left and amp[i] >= right:
            out.append((r[max(i - 1, 0)], r[min(i + 1, r.size - 1)]))
    return out


def refine_peak(system: System, r_grid, amplitudes, protocol: Protocol) -> tuple[float, float]:
    """(amplitude, r) of the sweep's largest protocol amplitude, refined between grid points.

    ``amplitudes`` are the grid's (from rest, under ``protocol``).  NaN when any grid run failed,
    as the grid's own maximum is then undefined.
    """
    r, amp = np.asarray(r_grid, dtype=float), np.asarray(amplitudes, dtype=float)
    if not np.all(np.isfinite(amp)):
        return math.nan, math.nan
    i = int(np.argmax(amp))
    best_amp, best_r = float(amp[i]), float(r[i])
    for lo, hi in _brackets(r, amp):
        seen = {}

        def minus_amplitude(x):
            seen[x] = simulate(system, float(x), protocol).amplitude
            return -seen[x] if math.isfinite(seen[x]) else 0.0

        minimize_scalar(minus_amplitude, bounds=(lo, hi), method="bounded",
                        options={"xatol": R_TOL, "maxiter": MAX_RUNS})
        for x, a in seen.items():
            if math.isfinite(a) and a > best_amp:
                best_amp, best_r = float(a), float(x)
    return best_amp, best_r


def add_readings(ds, systems, protocols) -> None:
    """Add the refined peak, and for a frictionless CID the closed-form and hybrid X_m, to a sweep dataset.

    ``systems``: the System of each gap ratio; ``protocols``: the Protocol of each start (runs from rest).
    """
    a_max = systems[0].a_max
    r = ds["freq_ratio"].values
    amp = ds["amplitude"].values
    dims = ("start", "gap_ratio")
    peaks = np.array([[refine_peak(system, r, amp[i, j], protocol) for j, system in enumerate(systems)]
                      for i, protocol in enumerate(protocols)])
    ds["x_max_refined"] = (dims, peaks[..., 0], {
        "units": ds["x_max"].attrs["units"],
        "long_name": "largest amplitude of the frequency sweep, refined between grid frequencies"})
    ds["X_m_refined"] = (dims, peaks[..., 0] / a_max, {"units": "1", "long_name": "refined amplitude ratio X_m"})
    ds["r_at_max_refined"] = (dims, peaks[..., 1], {
        "units": "1", "long_name": "frequency ratio of the refined largest amplitude"})
    if not is_free_mass(systems[0].kind) or systems[0].nu != 0.0:
        return
    closed = np.array([closed_form_sweep(system, r, protocols[0]) for system in systems])
    ds["amplitude_closed_form"] = (("gap_ratio", "freq_ratio"), closed, {
        "units": ds["amplitude"].attrs["units"],
        "long_name": "amplitude of the stable 2-EIPC closed-form orbit, measured as the protocol measures a "
                     "run (NaN where no stable, admissible orbit exists)"})
    best_closed = np.fmax.reduce(closed, axis=1)  # NaN only where no frequency has the orbit
    ds["X_m_closed_form"] = ("gap_ratio", best_closed / a_max, {
        "units": "1", "long_name": "X_m of the stable 2-EIPC closed form alone, over the grid frequencies "
                                   "where it exists (NaN: nowhere on the grid)"})
    hybrid = np.where(np.isfinite(closed)[None, :, :], closed[None, :, :], amp).max(axis=-1)
    ds["X_m_hybrid"] = (dims, hybrid / a_max, {
        "units": "1", "long_name": "X_m of the closed form where a stable 2-EIPC orbit exists, the "
                                   "simulation elsewhere"})
