"""Physics checks of the 2-EIPC closed form (impact.closed_form.masri) against masri.md.

Every check compares the closed form with something computed independently:
the exact flow and impact map (periodicity, fixed point, finite-difference
Jacobian, perturbation growth), the OCR's formula (D3), or the reference
ranges of masri.md section 9.
"""

import math

import numpy as np
import pytest

from impact.closed_form import masri
from impact.closed_form.masri import (
    BRANCHES,
    ImpactMapError,
    classify,
    exact_impact_map,
    masri_2eipc,
    orbit_initial_state,
    periodicity_residual,
)
from impact.model.params import ParameterError

BETA = 0.0048
XST = 0.096  # force_ratio = F0/K; gaps below are quoted as d/x_st like masri.md section 9

# (mu, e, r, d/x_st): resonance, below/above resonance, kappa2 < 0 (e > 1/(1+2 mu)),
# near the fold and a grazing (|lambda| >> 1) point.
POINTS = [
    (0.01, 0.5, 1.0, 150.0),
    (0.05, 0.5, 0.9, 27.72),
    (0.02, 0.8, 1.2, 50.0),
    (0.05, 0.25, 0.8, 10.0),
    (0.1, 0.95, 1.0, 20.0),   # e > 1/(1 + 2 mu) = 0.833
    (0.05, 0.9, 1.1, 10.0),   # e just below 1/(1 + 2 mu) = 0.909: Masri's sigma2 is large
    (0.05, 0.95, 0.85, 40.0),  # e > 0.909
    (0.01, 0.5, 1.0, 209.0),
]


def solve(mu, e, r, dx, beta=BETA):
    return masri_2eipc(mu, e, beta, r, dx * XST, XST)


def fixed_point(root):
    """Section-6.1 coordinates (t, x, xdot, ydot) of the orbit just after the +d/2 impact."""
    return np.array([0.0, root["x0"], root["v_plus"], root["u"]])


def map_args(sol, root):
    return (sol["mu"], sol["e"], sol["beta"], sol["r"], sol["gap"], sol["force_ratio"], root["force_phase"])


def scales(sol):
    """Natural units of (t, x, xdot, ydot): 1/Omega, A, A Omega, A Omega."""
    A, r = sol["A"], sol["r"]
    return np.array([1.0 / r, A, A * r, A * r])


def existing_roots(sol):
    return [(name, sol[name]) for name in BRANCHES if sol[name]["exists"]]


# ---------------------------------------------------------------- 1. periodicity

@pytest.mark.parametrize("mu,e,r,dx", POINTS)
def test_closed_form_is_periodic_under_exact_flow(mu, e, r, dx):
    """(P1)-(P5) hold to round-off for every real root, admissible or not."""
    sol = solve(mu, e, r, dx)
    roots = existing_roots(sol)
    assert roots, "the test point must have real roots"
    for _, root in roots:
        assert periodicity_residual(sol, root) <= 1e-12


@pytest.mark.parametrize("mu,e,r,dx", POINTS)
def test_admissible_root_is_fixed_point_of_exact_map(mu, e, r, dx):
    """An admissible root is a fixed point of the independent exact map G."""
    sol = solve(mu, e, r, dx)
    admissible = [root for _, root in existing_roots(sol) if root["admissible"]]
    assert admissible
    for root in admissible:
        w = fixed_point(root)
        gw = exact_impact_map(w, *map_args(sol, root))
        assert np.max(np.abs(gw - w) / scales(sol)) <= 1e-12


def test_kappa2_negative_point_is_covered():
    """At least one periodicity point has e > 1/(1 + 2 mu), where sigma2 < 0."""
    assert any(e > 1.0 / (1.0 + 2.0 * mu) for mu, e, _, _ in POINTS)
    sol = solve(0.1, 0.95, 1.0, 20.0)
    assert sol["upper"]["v_plus"] * sol["upper"]["v_minus"] < 0  # main-mass velocity reverses


def test_e_zero_is_periodic_and_separates():
    """e = 0 (section 4.4): plastic impact, the masses separate through xddot(0+) > 0."""
    sol = solve(0.01, 0.0, 1.0, 150.0)
    root = sol["upper"]
    assert root["admissible"] and root["departure_ok"]
    assert periodicity_residual(sol, root) <= 1e-12
    w = fixed_point(root)
    assert np.max(np.abs(exact_impact_map(w, *map_args(sol, root)) - w) / scales(sol)) <= 1e-12


# ---------------------------------------------------------------- 2. Jacobian

def fd_jacobian(sol, root, h, directions=None):
    """Richardson-extrapolated central differences of the exact map, scaled coordinates."""
    w, args, sc = fixed_point(root), map_args(sol, root), scales(sol)
    dirs = np.eye(4) if directions is None else np.asarray(directions, dtype=float)

    def central(step):
        cols = [(exact_impact_map(w + step * sc * d, *args) - exact_impact_map(w - step * sc * d, *args))
                / (2 * step) / sc for d in dirs]
        return np.column_stack(cols)

    return (4 * central(h / 2) - central(h)) / 3


def fd_step(sol, root):
    """Step well inside the linear range: it shrinks like (approach speed)^2 near grazing."""
    g = abs(root["u"] + root["v_minus"]) / (sol["A"] * sol["r"])
    return 1e-3 * min(1.0, g * g)


JAC_POINTS = [
    (0.05, 0.5, 0.9, 27.72, "upper"),
    (0.05, 0.5, 0.9, 27.72, "lower"),
    (0.02, 0.8, 1.2, 50.0, "upper"),
    (0.1, 0.95, 1.0, 20.0, "upper"),
    (0.05, 0.5, 0.9, 11.0, "lower"),   # |lambda| ~ 90
    (0.01, 0.5, 1.0, 209.0, "lower"),  # |lambda| ~ 1700, close to grazing
]


@pytest.mark.parametrize("mu,e,r,dx,branch", JAC_POINTS)
def test_analytic_jacobian_matches_finite_differences(mu, e, r, dx, branch):
    sol = solve(mu, e, r, dx)
    root = sol[branch]
    assert root["admissible"]
    sc = scales(sol)
    J = np.diag(1 / sc) @ np.array(root["jacobian"]) @ np.diag(sc)
    Jfd = fd_jacobian(sol, root, fd_step(sol, root))
    assert np.max(np.abs(Jfd - J)) / np.max(np.abs(J)) <= 1e-6


def test_jacobian_points_include_large_multiplier():
    moduli = [solve(mu, e, r, dx)[b]["max_modulus"] for mu, e, r, dx, b in JAC_POINTS]
    assert max(moduli) > 1e3 and min(moduli) < 1


def test_e_zero_jacobian_on_the_invariant_directions():
    """For e = 0 every impact leaves zdot = 0, so G is only defined off the wall
    along directions with d(xdot) = d(ydot); J must match there."""
    sol = solve(0.01, 0.0, 1.0, 150.0)
    root = sol["upper"]
    dirs = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1]]
    sc = scales(sol)
    J = np.diag(1 / sc) @ np.array(root["jacobian"]) @ np.diag(sc)
    Jfd = fd_jacobian(sol, root, 1e-4, dirs)
    assert np.max(np.abs(Jfd - J @ np.array(dirs, float).T)) / np.max(np.abs(J)) <= 1e-6
    assert min(root["eigenvalue_moduli"]) < 1e-12  # the image of G lies in zdot = 0


# ---------------------------------------------------------------- 3. dynamics of the map

def iterate_deviation(sol, root, eps, n, stop=1e-2, seed=1):
    """Scaled deviation from w* after each application of the exact map."""
    w0, args, sc = fixed_point(root), map_args(sol, root), scales(sol)
    d = np.random.default_rng(seed).normal(size=4)
    w = w0 + eps * sc * d / np.linalg.norm(d)
    out = []
    for _ in range(n):
        w = exact_impact_map(w, *args)
        out.append(np.linalg.norm((w - w0) / sc))
        if out[-1] > stop:
            break
    return np.array(out)


def test_stable_point_attracts():
    sol = solve(0.05, 0.5, 0.9, 27.72)
    root = sol["upper"]
    assert root["stable"]
    dev = iterate_deviation(sol, root, 1e-6, 400)
    assert len(dev) == 400 and dev[-1] < 1e-11
    k = np.arange(100, 300)  # decay per impact ~ max|lambda| (complex pair: fit over many turns)
    rate = np.exp(np.polyfit(k, np.log(dev[k]), 1)[0])
    assert rate == pytest.approx(root["max_modulus"], rel=0.02)


@pytest.mark.parametrize("mu,e,r,dx,branch", [(0.05, 0.5, 0.9, 27.72, "lower"),
                                              (0.02, 0.8, 1.2, 50.0, "upper")])
def test_unstable_point_repels_at_rate_max_lambda(mu, e, r, dx, branch):
    sol = solve(mu, e, r, dx)
    root = sol[branch]
    assert root["admissible"] and not root["stable"]
    dev = iterate_deviation(sol, root, 1e-9, 2000)
    assert dev[-1] > 1e-2  # left the orbit
    k = np.nonzero((dev > 1e-7) & (dev < 1e-3))[0]
    assert len(k) >= 10
    rate = np.exp(np.polyfit(k, np.log(dev[k]), 1)[0])
    assert rate == pytest.approx(root["max_modulus"], rel=0.01)


def test_inadmissible_root_breaks_the_pattern():
    """An extra-impact root: the exact map meets the +d/2 wall first."""
    sol = solve(0.01, 0.5, 1.0, 150.0)
    root = sol["lower"]
    assert not root["admissible"] and root["no_extra_impact_margin"] < 0
    with pytest.raises(ImpactMapError):
        exact_impact_map(fixed_point(root), *map_args(sol, root))


def test_fold_has_multiplier_plus_one():
    """Section 4.1: at d = d_max the roots merge and one lambda -> +1."""
    sol = solve(0.05, 0.5, 0.9, 1.0)
    near = masri_2eipc(0.05, 0.5, BETA, 0.9, sol["d_max"] * (1 - 1e-10), XST)
    for name in BRANCHES:
        assert np.min(np.abs(np.array(near[name]["eigenvalues"]) - 1.0)) < 1e-4
    assert near["upper"]["tau"] == pytest.approx(near["lower"]["tau"], abs=1e-4)
    beyond = masri_2eipc(0.05, 0.5, BETA, 0.9, sol["d_max"] * (1 + 1e-9), XST)
    assert not beyond["upper"]["exists"] and math.isnan(beyond["upper"]["amplitude"])
    assert classify(0.05, 0.5, BETA, 0.9, sol["d_max"] * (1 + 1e-9), XST) == 0


# ---------------------------------------------------------------- 4. OCR arctan (D3)

def masri_quoted_root(sol, tau):
    """Eqs. (7)-(8) replaced by Masri's quoted forms (section 3.5, corrected Delta):
    B1 = d/2 (1+h2)(sigma2-sigma1) Q/Delta, B2 = d/2 h1 (sigma1-sigma2) Q/Delta."""
    c = masri._constants(sol["mu"], sol["e"], sol["beta"], sol["r"], sol["gap"], sol["force_ratio"])
    beta, eta, r, h1, h2, A, d = (c[k] for k in ("beta", "eta", "r", "h1", "h2", "A", "gap"))
    th1, th2 = -beta * h1 + eta * h2, -beta * h2 - eta * h1
    s1, s2 = (math.pi / (2 * r)) / c["kappa1"], (math.pi / (2 * r)) / c["kappa2"]
    S, Q = math.sin(tau), r * math.cos(tau)
    delta = (h1 * (Q * (s2 - s1) - (S + Q * s2) * s1 * th2 + (S + Q * s1) * beta * s2)
             + (1 + h2) * ((S + Q * s2) * s1 * th1 + (S + Q * s1) * eta * s2))
    B1, B2 = d / 2 * (1 + h2) * (s2 - s1) * Q / delta, d / 2 * h1 * (s1 - s2) * Q / delta
    x0 = B2 + A * S
    u = -(2 * r / math.pi) * (x0 + d / 2)
    return dict(tau=tau, force_phase=tau + c["phi"], B1=B1, B2=B2, x0=x0, u=u,
                v_minus=c["kappa1"] * u, v_plus=c["kappa2"] * u)


def ocr_tau(sol, sign):
    """(denominator, principal-value tau) of the OCR's tan^-1[(-2 rho +- H R)/(-rho H -+ 2 R)]."""
    H, rho = sol["H"], sol["rho"]
    R = math.sqrt(H * H + 4 - rho * rho)
    den = -rho * H - sign * 2 * R
    return den, math.atan((-2 * rho + sign * H * R) / den)


OCR_POINTS = [p for p in POINTS if p[1] < 0.85]  # keep Masri's sigma2 away from its pole


@pytest.mark.parametrize("mu,e,r,dx", OCR_POINTS)
def test_masri_quoted_form_equals_regular_form(mu, e, r, dx):
    """Section 3.5: with the atan2 tau, Masri's B1, B2 (corrected Delta) equal eq. (7)."""
    sol = solve(mu, e, r, dx)
    for _, root in existing_roots(sol):
        quoted = masri_quoted_root(sol, root["tau"])
        for k in ("B1", "B2", "x0", "u"):
            assert quoted[k] == pytest.approx(root[k], rel=1e-8, abs=1e-12 * sol["A"])


@pytest.mark.parametrize("mu,e,r,dx", OCR_POINTS)
def test_principal_value_arctan_breaks_periodicity(mu, e, r, dx):
    """D3: where the denominator is negative, arctan gives tau + pi and the
    orbit misses periodicity by a macroscopic amount; atan2 is exact."""
    sol = solve(mu, e, r, dx)
    seen_negative = False
    for name, sign in (("upper", 1.0), ("lower", -1.0)):
        if not sol[name]["exists"]:
            continue
        den, tau_pv = ocr_tau(sol, sign)
        res_pv = periodicity_residual(sol, masri_quoted_root(sol, tau_pv))
        res_atan2 = periodicity_residual(sol, masri_quoted_root(sol, sol[name]["tau"]))
        assert res_atan2 <= 1e-9
        if den < 0:
            seen_negative = True
            assert abs(abs(tau_pv - sol[name]["tau"]) - math.pi) < 1e-9
            assert res_pv > 1e-2  # O(1e-2 .. 1) in units of A, vs ~1e-15 with atan2
            c = masri._constants(mu, e, BETA, r, dx * XST, XST)  # the regular eq. (7) fails too
            regular = masri._root_from_phase(c, math.sin(tau_pv), math.cos(tau_pv) / c["Lambda"])
            assert periodicity_residual(sol, regular) > 1e-2
        else:
            assert tau_pv == pytest.approx(sol[name]["tau"], abs=1e-12)
    assert seen_negative


# ---------------------------------------------------------------- 5. limits and reference ranges

def finite_numbers(root):
    keys = ("tau", "force_phase", "amplitude", "u", "x0", "v_minus", "v_plus", "B1", "B2")
    return all(math.isfinite(root[k]) for k in keys) and all(map(math.isfinite, root["eigenvalue_moduli"]))


def test_zero_gap_limit_is_finite_and_continuous():
    zero = masri_2eipc(0.05, 0.5, BETA, 0.9, 0.0, XST)
    tiny = masri_2eipc(0.05, 0.5, BETA, 0.9, 1e-9, XST)
    for name in BRANCHES:
        assert finite_numbers(zero[name])
        assert not zero[name]["admissible"]  # no room for a free flight at d = 0
        for k in ("tau", "x0", "u", "B1", "B2", "amplitude"):
            assert zero[name][k] == pytest.approx(tiny[name][k], rel=1e-6, abs=1e-9)
        assert periodicity_residual(zero, zero[name]) <= 1e-12


def test_lambda_to_zero_limit_is_finite_and_continuous():
    """Lambda = 0 only for beta = 0 and e = 1 (H infinite): the regular form stays finite."""
    exact = masri_2eipc(0.05, 1.0, 0.0, 0.8, 0.5, XST)
    near = masri_2eipc(0.05, 1.0 - 1e-9, 0.0, 0.8, 0.5, XST)
    assert exact["Lambda"] == 0.0 and math.isinf(exact["d_max"])
    for name in BRANCHES:
        assert finite_numbers(exact[name])
        assert periodicity_residual(exact, exact[name]) <= 1e-12
        assert exact[name]["x0"] == pytest.approx(near[name]["x0"], rel=1e-6)


def test_lambda_positive_for_damped_system():
    """Lambda >= 2 mu beta e^{-beta T}(eta T + sin eta T) > 0, so H is finite for beta > 0."""
    rng = np.random.default_rng(0)
    for _ in range(2000):
        mu, e = 10 ** rng.uniform(-3, 0), rng.uniform(0, 1)
        beta, r = 10 ** rng.uniform(-5, -0.5), 10 ** rng.uniform(-1, 1)
        c = masri._constants(mu, e, beta, r, 1.0, 1.0)
        T, eta = math.pi / r, math.sqrt(1 - beta * beta)
        bound = 2 * mu * beta * math.exp(-beta * T) * (eta * T + math.sin(eta * T))
        assert c["Lambda"] >= bound * (1 - 1e-9)


def test_resonance_band_matches_section9_table():
    """mu = 0.01, e = 0.5, r = 1: stable gaps inside 98-231 x_st, amplitude ratio 8-45."""
    gaps = np.arange(60.0, 280.0, 2.0)
    stable = [(dx, s["upper"]["amplitude_over_static"]) for dx in gaps
              for s in [solve(0.01, 0.5, 1.0, dx)] if s["upper"]["stable"] or s["lower"]["stable"]]
    assert len(stable) >= 20
    d_band = [dx for dx, _ in stable]
    ratios = [a for _, a in stable]
    assert min(d_band) >= 98 * 0.97 and max(d_band) <= 231 * 1.03
    assert min(ratios) >= 8 * 0.97 and max(ratios) <= 45 * 1.03
    assert all(classify(0.01, 0.5, BETA, 1.0, dx * XST, XST) == 3 for dx in d_band)
    bare = 1.0 / (2 * BETA)
    assert max(ratios) < 0.5 * bare  # the damper works at resonance


def test_section9_two_admissible_roots_example():
    """mu = 0.05, e = 0.5, r = 0.9, d = 27.72: stable 7.53 and unstable 3.61."""
    sol = solve(0.05, 0.5, 0.9, 27.72)
    assert sol["upper"]["stable"] and sol["upper"]["amplitude_over_static"] == pytest.approx(7.53, abs=0.01)
    assert sol["lower"]["admissible"] and not sol["lower"]["stable"]
    assert sol["lower"]["amplitude_over_static"] == pytest.approx(3.61, abs=0.01)
    assert classify(0.05, 0.5, BETA, 0.9, 27.72 * XST, XST) == 3


def test_small_gap_has_no_admissible_root():
    assert classify(0.01, 0.5, BETA, 1.0, 10 * XST, XST) == 1


def test_orbit_initial_state_sits_on_the_wall():
    sol = solve(0.05, 0.5, 0.9, 27.72)
    x, xd, y, yd = orbit_initial_state(sol["upper"], sol["gap"])
    assert y - x == pytest.approx(sol["gap"] / 2, abs=1e-15)
    assert (x, xd, yd) == (sol["upper"]["x0"], sol["upper"]["v_plus"], sol["upper"]["u"])
    assert yd - xd < 0  # moving away from the +d/2 wall


@pytest.mark.parametrize("dx,corner", [(20.0, False), (26.34, True)])
def test_amplitude_covers_the_orbit(dx, corner):
    """X of section 5 equals max |x| on a dense sample of the exact flow; for
    kappa2 < 0 it can be the corner at the impact (|x0|)."""
    sol = solve(0.1, 0.95, 1.0, dx)
    root = sol["upper"]
    assert root["stable"]
    t = np.linspace(0, math.pi / sol["r"], 20001)
    x, _ = masri.forced_flow(0.0, root["x0"], root["v_plus"], t, BETA, sol["r"], XST, root["force_phase"])
    assert root["amplitude"] == pytest.approx(np.max(np.abs(x)), rel=1e-7)
    assert (root["amplitude"] == abs(root["x0"])) is corner


def test_stability_requires_admissibility():
    """A root with all |lambda| < 1 but an extra impact / sticking is not stable (D8)."""
    sol = solve(0.01, 0.0, 1.0, 87.15)
    root = sol["upper"]
    assert root["max_modulus"] < 1 and not root["admissible"] and not root["stable"]
    assert "sticks" in root["reason"] and not root["departure_ok"] and root["approach_ok"]
    assert classify(0.01, 0.0, BETA, 1.0, 87.15 * XST, XST) < 3


def test_missing_roots_are_nan_with_the_same_keys():
    there = solve(0.05, 0.5, 0.9, 27.72)["upper"]
    missing = solve(0.05, 0.5, 0.9, 1e4)["upper"]
    assert set(there) == set(missing)
    assert not missing["exists"] and not missing["admissible"] and not missing["stable"]
    assert all(math.isnan(missing[k]) for k in ("tau", "x0", "u", "amplitude", "B1"))
    assert all(math.isnan(v) for v in missing["eigenvalue_moduli"])


@pytest.mark.parametrize("kw", [dict(e=1.5), dict(mu=0.0), dict(gap=-1.0), dict(beta=0.0, r=1.0),
                                dict(beta=0.0, r=1 / 3)])
def test_bad_input_is_refused(kw):
    args = dict(mu=0.05, e=0.5, beta=BETA, r=0.9, gap=1.0, force_ratio=XST) | kw
    with pytest.raises(ParameterError):
        masri_2eipc(**args)
