"""Masri's closed-form 2-EIPC steady state of the classical impact damper.

Implements ``docs/masri.md`` (sections 3.4, 4, 5, 6 and 7): the
steady motion with two equally spaced impacts per forcing cycle, whether it is
physically admissible, the main-mass amplitude, and the eigenvalues of the
impact-to-impact Poincare map that decide its stability.

Model units (``model.md``): omega = 1, M = 1, the force amplitude enters as the
static deflection ``force_ratio`` = F0/K (so F0/M = force_ratio), ``gap`` = d
is the total clearance, the walls sit at z = y - x = +-d/2.

Conventions kept from masri.md:

* ``tau`` is the phase of the forced *response* at the impact on the +d/2
  wall; the force there is F0 sin(Omega t + psi) with psi = tau + phi
  (``force_phase``), phi = atan2(2 beta r, 1 - r^2) (masri.md D1).
* "upper"/"lower" are the upper/lower signs of eq. (6) with a four-quadrant
  atan2 (D3).

The regular forms (5)-(8) are used throughout.  They are evaluated in the
homogeneous form of section 3.4 (everything multiplied by Lambda^2), so
nothing is divided by Lambda and the Lambda -> 0 limit is finite.  For
0 <= e <= 1 and beta > 0, Lambda > 0 strictly (proof in ``_constants``);
Lambda = 0 needs beta = 0 and e = 1 (or beta = 0 at r = 1/(2k+1), where
H's numerator vanishes too), so H is finite for every damped structure.
The labels are those of eq. (6) taken from the Lambda -> 0+ side.

``exact_impact_map`` is an independent implementation of the map G of section
6.1 (closed-form flow, root-found impact, impact law, mirror) for checking the
closed form and its analytic Jacobian.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from impact.model.params import ParameterError

N_GRID = 4000  # samples per half period for the extremum searches (masri.md 4.3)
BRANCHES = ("upper", "lower")
_SIGNS = {"upper": +1.0, "lower": -1.0}
_ROOT_KEYS = ("tau", "force_phase", "sin_tau", "cos_tau", "amplitude", "amplitude_over_static", "u",
              "x0", "v_minus", "v_plus", "B1", "B2", "no_extra_impact_margin")


class ImpactMapError(RuntimeError):
    """The exact map left the 2-EIPC pattern (wrong wall, penetration, no impact)."""


# --------------------------------------------------------------------------
# parameters and constants of section 1
# --------------------------------------------------------------------------

def _validate(mu, e, beta, r, gap, force_ratio):
    """Refuse input outside the model's domain with the field's name (params.py style)."""
    checks = (("mu", mu, mu > 0), ("e", e, 0 <= e <= 1), ("beta", beta, 0 <= beta < 1),
              ("r", r, r > 0), ("gap", gap, gap >= 0), ("force_ratio", force_ratio, force_ratio > 0))
    for name, value, ok in checks:
        if not (math.isfinite(value) and ok):
            raise ParameterError(f"{name} = {value!r} is out of range for the 2-EIPC closed form")
    if beta == 0 and r == 1:
        raise ParameterError("beta = 0 with r = 1 is the singular undamped resonance (A = inf)")
    n = round(1.0 / r)
    if beta == 0 and n % 2 == 1 and abs(n * r - 1.0) < 1e-12:
        raise ParameterError(f"beta = 0 with r = 1/{n} is degenerate: Lambda = H's numerator = 0")


def _constants(mu, e, beta, r, gap, force_ratio) -> dict:
    """All gap- and phase-independent quantities of masri.md section 1 and eq. (5).

    Hnum = pi eta G^2 + 4 mu r h1 is H's numerator, so H = Hnum / Lambda.
    """
    eta = math.sqrt(1.0 - beta * beta)
    T = math.pi / r
    A = force_ratio / math.hypot(1.0 - r * r, 2.0 * beta * r)
    decay = math.exp(-beta * T)
    h1, h2 = decay * math.sin(eta * T), decay * math.cos(eta * T)
    k1 = (1.0 - e + 2.0 * mu) / (1.0 + e)
    k2 = (1.0 - e - 2.0 * mu * e) / (1.0 + e)
    G2 = h1 * h1 + (1.0 + h2) ** 2
    # Lambda >= Lambda(e=1) = mu e^{-beta T} [2 eta sinh(beta T) + 2 beta sin(eta T)]
    # >= 2 mu beta e^{-beta T} (eta T + sin eta T) > 0, so a negative value is
    # round-off (beta = 0, e = 1); clamping keeps the eq.-(6) labels continuous.
    lam = max(k2 * eta * G2 + 2.0 * mu * (beta * h1 + eta * (1.0 + h2)), 0.0)
    hnum = math.pi * eta * G2 + 4.0 * mu * r * h1
    return dict(mu=mu, e=e, beta=beta, r=r, gap=gap, force_ratio=force_ratio,
                eta=eta, T=T, A=A, phi=math.atan2(2.0 * beta * r, 1.0 - r * r),
                h1=h1, h2=h2, kappa1=k1, kappa2=k2, G2=G2, Lambda=lam, Hnum=hnum,
                rho=gap / A)


def _existence(c) -> dict:
    """H, rho_max, d_max and the discriminant S^2 = Lambda^2 (H^2 + 4 - rho^2).

    Keeping S^2 (not R^2) avoids the division by Lambda; at Lambda = 0 the
    roots exist for every gap (d_max = inf).
    """
    lam, hnum, rho = c["Lambda"], c["Hnum"], c["rho"]
    W = hnum * hnum + 4.0 * lam * lam
    S2 = hnum * hnum + (4.0 - rho * rho) * lam * lam
    if lam != 0.0:
        H, rho_max = hnum / lam, math.sqrt(W) / abs(lam)
    else:
        H, rho_max = math.copysign(math.inf, hnum), math.inf
    return dict(H=H, rho_max=rho_max, d_max=c["A"] * rho_max, W=W, S2=S2)


# --------------------------------------------------------------------------
# the closed-form roots, eqs. (6)-(8)
# --------------------------------------------------------------------------

def _root_phase(c, ex, sign) -> tuple[float, float]:
    """(sin tau, cos tau / Lambda) of the eq.-(6) root with the given sign.

    Eq. (6) times Lambda^2 (Lambda >= 0, see _constants):
    sin tau = (-2 rho Lambda^2 + sign Hnum S)/W and
    cos tau / Lambda = (-rho Hnum - 2 sign S)/W, with S = sqrt(S2) and
    W = Hnum^2 + 4 Lambda^2.  Regular at Lambda = 0, and the B's of eq. (7)
    need exactly cos tau / Lambda.
    """
    lam, hnum, rho = c["Lambda"], c["Hnum"], c["rho"]
    S = math.sqrt(max(ex["S2"], 0.0))
    W = ex["W"]
    return (-2.0 * rho * lam * lam + sign * hnum * S) / W, (-rho * hnum - 2.0 * sign * S) / W


def _root_from_phase(c, sin_tau, cos_over_lambda) -> dict:
    """Eqs. (7)-(8): B1, B2, x0, u, v_-, v_+ and the phases for one root."""
    mu, r, A, gap = c["mu"], c["r"], c["A"], c["gap"]
    cos_tau = c["Lambda"] * cos_over_lambda
    tau = math.atan2(sin_tau, cos_tau)
    k = 2.0 * mu * r * A * cos_over_lambda
    B1, B2 = -k * (1.0 + c["h2"]), k * c["h1"]
    x0 = B2 + A * sin_tau
    u = -(2.0 * r / math.pi) * (x0 + 0.5 * gap)
    return dict(tau=tau, force_phase=tau + c["phi"], sin_tau=sin_tau, cos_tau=cos_tau,
                B1=B1, B2=B2, x0=x0, u=u, v_minus=c["kappa1"] * u, v_plus=c["kappa2"] * u)


def _orbit_x(c, root, t):
    """Main-mass displacement and velocity on 0 <= t <= T from eq. (3)."""
    t = np.asarray(t, dtype=float)
    beta, eta, r, A = c["beta"], c["eta"], c["r"], c["A"]
    B1, B2, tau = root["B1"], root["B2"], root["tau"]
    ex, sn, cs = np.exp(-beta * t), np.sin(eta * t), np.cos(eta * t)
    x = ex * (B1 * sn + B2 * cs) + A * np.sin(r * t + tau)
    xd = ex * ((-beta * B1 - eta * B2) * sn + (eta * B1 - beta * B2) * cs) + A * r * np.cos(r * t + tau)
    return x, xd


def _interior_roots(f, T) -> list[float]:
    """Roots of f on (0, T): sign changes on an N_GRID grid, refined with Brent.

    Used for the extrema of z (no-extra-impact check) and of x (amplitude).
    """
    t = np.linspace(0.0, T, N_GRID + 1)[1:-1]
    y = f(t)
    idx = np.nonzero(y[:-1] * y[1:] <= 0.0)[0]
    return [brentq(f, t[i], t[i + 1], xtol=1e-14, rtol=4 * np.finfo(float).eps) for i in idx]


# --------------------------------------------------------------------------
# admissibility (section 4) and amplitude (section 5)
# --------------------------------------------------------------------------

def _extra_impact_margin(c, root) -> float:
    """min (d/2 - |z(t*)|)/(d/2) over the interior extrema t* of z; 1 if z is monotone.

    z(t) = y0 + u t - x(t) runs from +d/2 to -d/2, so an extra impact can only
    happen at an interior extremum (section 4.3).  d = 0 leaves no room at all
    (z must have an extremum by Rolle), hence -inf.
    """
    half = 0.5 * c["gap"]
    y0, u = root["x0"] + half, root["u"]
    zdot = lambda t: u - _orbit_x(c, root, t)[1]  # noqa: E731
    stars = _interior_roots(zdot, c["T"])
    if not stars:
        return 1.0
    if half == 0.0:
        return -math.inf
    z = y0 + u * np.array(stars) - _orbit_x(c, root, stars)[0]
    return float(np.min((half - np.abs(z)) / half))


def _accel_after_impact(c, root) -> float:
    """a0 = xddot(0+) from the equation of motion (section 6.2)."""
    return (c["force_ratio"] * math.sin(root["force_phase"])
            - 2.0 * c["beta"] * root["v_plus"] - root["x0"])


def _admissibility(c, root) -> dict:
    """Conditions 2-4 of section 4, with the e = 0 second-order departure check.

    For e > 0, zdot(0+) = (1 - kappa2) u < 0 follows from v_- < 0.  For e = 0
    the masses leave the impact together (zdot(0+) = 0) and separate only if
    zddot(0+) = -xddot(0+) < 0, i.e. a0 > 0; otherwise the free mass would
    stick to the wall and the motion is not 2 EIPC.
    """
    approach = root["v_minus"] < 0.0
    departure = approach if c["e"] > 0.0 else (approach and _accel_after_impact(c, root) > 0.0)
    margin = _extra_impact_margin(c, root)
    reasons = []
    if not approach:
        reasons.append("v_minus >= 0: the masses separate at the 'impact'")
    elif not departure:
        reasons.append("e = 0 and xddot(0+) <= 0: the free mass sticks to the wall")
    if not margin > 0.0:
        reasons.append(f"extra impact inside the half period (margin {margin:.3g})")
    return dict(approach_ok=bool(approach), departure_ok=bool(departure),
                no_extra_impact_margin=margin, admissible=not reasons, reason="; ".join(reasons))


def _amplitude(c, root) -> float:
    """X = max |x| over [0, T]: |x0| or an interior extremum (section 5)."""
    stars = _interior_roots(lambda t: _orbit_x(c, root, t)[1], c["T"])
    values = [abs(root["x0"])]
    if stars:
        values.extend(np.abs(_orbit_x(c, root, stars)[0]).tolist())
    return float(max(values))


# --------------------------------------------------------------------------
# stability: the analytic Jacobian of section 6.2
# --------------------------------------------------------------------------

def _transition_matrix(c) -> np.ndarray:
    """Phi = E(T), the homogeneous (xi, xi') transition over a half period (omega = 1)."""
    h1, h2, q = c["h1"], c["h2"], c["beta"] / c["eta"]
    return np.array([[h2 + q * h1, h1 / c["eta"]],
                     [-h1 / c["eta"], h2 - q * h1]])


def _impact_matrix(mu, e) -> np.ndarray:
    """Eq. (2) as a matrix acting on (xdot_-, ydot_-): rows (a, b) and (c, c_hat)."""
    return np.array([[1.0 - mu * e, mu * (1.0 + e)],
                     [1.0 + e, mu - e]]) / (1.0 + mu)


def _jacobian(c, root) -> np.ndarray:
    """J = DG(w*) of section 6.2, w = (t, x, xdot, ydot) just after a +d/2 impact.

    (a) the next impact time moves by g . dw, (b) the pre-impact main-mass
    state by D dw, (c) the impact law and the mirror finish the step.
    """
    F, beta, T = c["force_ratio"], c["beta"], c["T"]
    x0, u, vm, vp = root["x0"], root["u"], root["v_minus"], root["v_plus"]
    Phi = _transition_matrix(c)
    sin_psi = math.sin(root["force_phase"])
    f0 = np.array([vp, F * sin_psi - 2.0 * beta * vp - x0])
    fT = np.array([-vm, -F * sin_psi + 2.0 * beta * vm + x0])
    g = np.array([u - Phi[0] @ f0, Phi[0, 0] - 1.0, Phi[0, 1], -T]) / (u + vm)
    D = np.column_stack([-Phi @ f0, Phi, np.zeros(2)]) + np.outer(fT, g)
    (a, b), (cc, ch) = _impact_matrix(c["mu"], c["e"])
    e4 = np.array([0.0, 0.0, 0.0, 1.0])
    rows = np.vstack([g, D[0], a * D[1] + b * e4, cc * D[1] + ch * e4])
    return np.diag([1.0, -1.0, -1.0, -1.0]) @ rows


def _stability(c, root, admissible) -> dict:
    """Eigenvalues of J; stable iff admissible and all |lambda| < 1 (section 6.1)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        J = _jacobian(c, root)
    if not np.all(np.isfinite(J)):
        # a grazing impact (u + v_- = 0): the next impact time is not
        # differentiable and |lambda| -> infinity (section 6.3)
        inf = [math.inf] * 4
        return dict(jacobian=J.tolist(), eigenvalues=[complex(math.inf)] * 4, eigenvalue_moduli=inf,
                    max_modulus=math.inf, stable=False)
    lam = np.linalg.eigvals(J)
    lam = lam[np.argsort(-np.abs(lam))]
    moduli = np.abs(lam)
    return dict(jacobian=J.tolist(), eigenvalues=[complex(z) for z in lam],
                eigenvalue_moduli=moduli.tolist(), max_modulus=float(moduli[0]),
                stable=bool(admissible and moduli[0] < 1.0))


# --------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------

def _missing_root(reason: str) -> dict:
    """A root that does not exist: flags False, every number NaN."""
    nan = math.nan
    out = {k: nan for k in _ROOT_KEYS}
    out.update(exists=False, admissible=False, approach_ok=False, departure_ok=False,
               stable=False, reason=reason, max_modulus=nan,
               eigenvalues=[complex(nan, nan)] * 4, eigenvalue_moduli=[nan] * 4,
               jacobian=[[nan] * 4 for _ in range(4)])
    return out


def _analyse_root(c, ex, sign) -> dict:
    """One branch of eq. (6): orbit, admissibility, amplitude and stability."""
    root = _root_from_phase(c, *_root_phase(c, ex, sign))
    root.update(_admissibility(c, root))
    root["amplitude"] = _amplitude(c, root)
    root["amplitude_over_static"] = root["amplitude"] / c["force_ratio"]
    root.update(_stability(c, root, root["admissible"]))
    root["exists"] = True
    return root


def masri_2eipc(mu, e, beta, r, gap, force_ratio=0.096) -> dict:
    """Both closed-form 2-EIPC roots with admissibility, amplitude and stability.

    Returns the inputs, H, rho, rho_max, d_max, A, phi (and Lambda), plus
    ``upper``/``lower`` dicts (upper/lower signs of eq. 6).  Each root dict has
    exists, admissible, approach_ok, departure_ok, no_extra_impact_margin,
    reason ('' if admissible), stable, tau, force_phase, sin_tau, cos_tau,
    amplitude, amplitude_over_static, u, x0, v_minus, v_plus, B1, B2, eigenvalues
    (sorted by decreasing modulus), eigenvalue_moduli, max_modulus and
    jacobian (4x4, coordinates (t, x, xdot, ydot) after a +d/2 impact).
    Gaps, amplitudes and velocities are in model units (omega = 1).
    """
    mu, e, beta, r, gap, force_ratio = map(float, (mu, e, beta, r, gap, force_ratio))
    _validate(mu, e, beta, r, gap, force_ratio)
    c = _constants(mu, e, beta, r, gap, force_ratio)
    ex = _existence(c)
    out = {k: c[k] for k in ("mu", "e", "beta", "r", "gap", "force_ratio", "rho", "A", "phi", "Lambda")}
    out.update(H=ex["H"], rho_max=ex["rho_max"], d_max=ex["d_max"])
    if ex["W"] == 0.0 or ex["S2"] < 0.0:
        reason = ("degenerate: Lambda = Hnum = 0 (beta = 0 at r = 1/(2k+1))" if ex["W"] == 0.0
                  else "no real root: d > d_max")
        for name in BRANCHES:
            out[name] = _missing_root(reason)
        return out
    for name in BRANCHES:
        out[name] = _analyse_root(c, ex, _SIGNS[name])
    return out


def orbit_initial_state(sol_root, gap) -> tuple[float, float, float, float]:
    """(x, xdot, y, ydot) just after the impact at t = 0 on the +d/2 wall.

    Start a simulator here at t = 0 with force F0 sin(Omega t + force_phase)
    to run on the closed-form orbit.
    """
    x0 = float(sol_root["x0"])
    return x0, float(sol_root["v_plus"]), x0 + 0.5 * float(gap), float(sol_root["u"])


def classify(mu, e, beta, r, gap, force_ratio=0.096) -> int:
    """Stability-chart class of the best branch.

    0 no real root, 1 roots but none admissible, 2 admissible but unstable,
    3 admissible and stable.
    """
    sol = masri_2eipc(mu, e, beta, r, gap, force_ratio)
    roots = [sol[name] for name in BRANCHES]
    if not any(s["exists"] for s in roots):
        return 0
    if any(s["stable"] for s in roots):
        return 3
    return 2 if any(s["admissible"] for s in roots) else 1


# --------------------------------------------------------------------------
# independent exact impact map (section 6.1)
# --------------------------------------------------------------------------

def forced_flow(t0, x, xdot, t, beta, r, force_ratio, phase_psi):
    """Exact (x, xdot)(t) of x'' + 2 beta x' + x = F sin(r t + psi) from (x, xdot) at t0.

    Closed form: the steady forced part A sin(r t + psi - phi) plus the free
    damped oscillation that matches the initial state.  Written independently
    of the closed-form orbit (no B's, no transition matrix) for verification.
    """
    t = np.asarray(t, dtype=float)
    eta = math.sqrt(1.0 - beta * beta)
    amp = force_ratio / math.hypot(1.0 - r * r, 2.0 * beta * r)
    lag = math.atan2(2.0 * beta * r, 1.0 - r * r)
    c2 = x - amp * math.sin(r * t0 + phase_psi - lag)
    c1 = (xdot - amp * r * math.cos(r * t0 + phase_psi - lag) + beta * c2) / eta
    s = t - t0
    ex, sn, cs = np.exp(-beta * s), np.sin(eta * s), np.cos(eta * s)
    xs = ex * (c1 * sn + c2 * cs) + amp * np.sin(r * t + phase_psi - lag)
    vs = ex * ((eta * c1 - beta * c2) * cs - (beta * c1 + eta * c2) * sn) \
        + amp * r * np.cos(r * t + phase_psi - lag)
    return xs, vs


def impact_law(xdot_minus, ydot_minus, mu, e) -> tuple[float, float]:
    """Eq. (2): post-impact velocities (momentum + Newton restitution)."""
    xp = ((1.0 - mu * e) * xdot_minus + mu * (1.0 + e) * ydot_minus) / (1.0 + mu)
    yp = ((1.0 + e) * xdot_minus + (mu - e) * ydot_minus) / (1.0 + mu)
    return xp, yp


def _first_lower_wall_time(zfun, zdot, t0, T, half, tol, n=256, max_half_periods=40):
    """Time of the first crossing z = -d/2 after t0, robust to grazing.

    Scans half periods on an n-point grid; in every cell an interior extremum
    of z (sign change of zdot, refined by Brent) is checked as well as the
    cell's end, so a dip through the wall between samples is not missed.  A
    contact with the +d/2 wall first (or leaving it outwards) raises; ``tol``
    absorbs round-off at the start, where z = d/2 and, for e = 0, zdot = 0.
    """
    brent = dict(xtol=1e-15, rtol=4 * np.finfo(float).eps)
    for k in range(max_half_periods):
        ts = t0 + T * (k + np.linspace(0.0, 1.0, n + 1))
        zs, zds = zfun(ts), zdot(ts)
        for i in range(n):
            left = ts[i]
            if zds[i] * zds[i + 1] < 0.0:
                ts_ext = brentq(zdot, ts[i], ts[i + 1], **brent)
                z_ext = zfun(ts_ext)
                if z_ext <= -half:
                    return brentq(lambda t: zfun(t) + half, ts[i], ts_ext, **brent)
                if z_ext > half + tol:
                    raise ImpactMapError("the next contact is with the +d/2 wall")
                left = ts_ext
            if zs[i + 1] <= -half:
                return brentq(lambda t: zfun(t) + half, left, ts[i + 1], **brent)
            if zs[i + 1] > half + tol:
                raise ImpactMapError("the free mass leaves through the +d/2 wall")
    raise ImpactMapError("no impact on the -d/2 wall within the search horizon")


def exact_impact_map(w, mu, e, beta, r, gap, force_ratio, phase_psi) -> np.ndarray:
    """G = M o P of section 6.1 evaluated exactly (no linearisation).

    w = (t, x, xdot, ydot) just after an impact on the +d/2 wall (y = x + d/2).
    Flow in closed form, find the next impact on the -d/2 wall by root
    finding (plus one Newton polish), apply eq. (2), then mirror
    (t - T, -x, -xdot, -ydot).  Raises ImpactMapError if the motion leaves
    the 2-EIPC pattern.
    """
    t0, x, xd, yd = (float(v) for v in w)
    half, T = 0.5 * gap, math.pi / r

    def flow(t):
        return forced_flow(t0, x, xd, t, beta, r, force_ratio, phase_psi)

    def zfun(t):
        return x + half + yd * (np.asarray(t) - t0) - flow(t)[0]

    def zdot(t):
        return yd - flow(t)[1]

    tol = 64.0 * np.finfo(float).eps * (half + abs(x) + (abs(xd) + abs(yd)) * T)
    t1 = _first_lower_wall_time(zfun, zdot, t0, T, half, tol)
    slope = zdot(t1)
    if slope != 0.0:
        t1 -= (zfun(t1) + half) / slope  # Newton polish to full precision
    x1, xd1 = (float(v) for v in flow(t1))
    xdp, ydp = impact_law(xd1, yd, mu, e)
    return np.array([t1 - T, -x1, -xdp, -ydp])


def periodicity_residual(c_or_sol, root) -> float:
    """Max violation of (P1)-(P5) by a root, in units of A (velocities of A Omega).

    Flows the exact equations over T from the post-impact state (x0, v_+) with
    force phase ``force_phase`` and checks x(T) = -x0, xdot(T-) = -v_-,
    z(T) = -d/2, and that eq. (2) maps (xdot(T-), u) to (-v_+, -u).
    ``c_or_sol`` is the top-level dict of masri_2eipc (or anything with the
    same input keys).
    """
    s = c_or_sol
    mu, e, beta, r, gap, F = (s[k] for k in ("mu", "e", "beta", "r", "gap", "force_ratio"))
    A, T = F / math.hypot(1.0 - r * r, 2.0 * beta * r), math.pi / r
    x0, vm, vp, u = root["x0"], root["v_minus"], root["v_plus"], root["u"]
    xT, vT = (float(v) for v in forced_flow(0.0, x0, vp, T, beta, r, F, root["force_phase"]))
    zT = x0 + 0.5 * gap + u * T - xT
    xp, yp = impact_law(vT, u, mu, e)
    res = [abs(xT + x0) / A, abs(vT + vm) / (A * r), abs(zT + 0.5 * gap) / A,
           abs(xp + vp) / (A * r), abs(yp + u) / (A * r)]
    return float(max(res))


_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)  # Gauss-Legendre nodes per piece of the orbit


def orbit_rms_amplitude(root: dict, mu, e, beta, r, gap, force_ratio, pieces=64) -> float:
    """sqrt(2) * RMS of x over the closed-form orbit's half period (x(t+T) = -x(t))."""
    T = math.pi / r
    x0, v0 = float(root["x0"]), float(root["v_plus"])
    edges = np.linspace(0.0, T, pieces + 1)
    total = 0.0
    for a, b in zip(edges[:-1], edges[1:]):
        t = 0.5 * (a + b) + 0.5 * (b - a) * _GL_X
        x = forced_flow(0.0, x0, v0, t, beta, r, force_ratio, float(root["force_phase"]))[0]
        total += 0.5 * (b - a) * np.sum(_GL_W * x * x)
    return math.sqrt(2.0 * total / T)
