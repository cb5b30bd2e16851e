"""A virtual test rig: a higher-fidelity model of the paper's 1.5 Hz PID test stand.

Everything this module produces is **synthetic** (``synthetic: true`` and a
``virtual rig`` provenance in every record header).  It is not the paper's
data -- those records are not public -- but a second, more detailed model of
the same stand, used to cross-validate the paper's Eq. (4) model
(:mod:`impact.stages.validation.comparison`).

What the rig models beyond Eq. (4)
----------------------------------
* **Nonlinear pendulum in the accelerating frame, coupled back.**  The ball
  hangs from a hook on the moving structure (displacement x) at angle theta.
  With the ball centre at distance L below the hook, ball mass m, its moment of
  inertia about its own centre I_c = 2/5 m a^2 (a = ball radius, the ball kept
  aligned with the taut string: a compound pendulum) and the structure's mass,
  stiffness and damping M, K, C, Lagrange's equations are

      (M + m) x'' + m L cos(th) th'' - m L sin(th) th'^2 + C x' + K x = F0 sin(Omega t + phi)
      m L cos(th) x'' + (m L^2 + I_c) th'' + m g L sin(th)              = F_b L cos(th)

  F_b is the wall's horizontal force on the ball (and -F_b acts on the
  structure through the wall).  Linearised (sin th = th, cos th = 1, no th'^2),
  with I_c = 0 and L = g / omega_p^2, and y = x + L th, these are exactly
  Eq. (4) -- the rig's fidelity switches turn each addition off.
* **Finite ball radius.**  The walls are vertical; the ball touches a wall
  when its surface reaches it, i.e. when the horizontal offset of its centre,
  s = L sin(th), reaches +-d/2 (d = total clearance = free travel of the ball,
  the paper's definition).  The radius enters through the rotational inertia
  I_c and through the pendulum length: with ``length_rule: compound`` (default)
  L is chosen so that the small-angle frequency of the compound pendulum,
  sqrt(g L / (L^2 + 2/5 a^2)), equals r' omega (the experimenter tunes by the
  measured pendulum frequency); ``point_mass`` uses L = g / omega_p^2 (the
  paper's formula with l_p = hook-to-centre distance, which then detunes the
  big balls by up to ~1 %).
* **Compliant contact (Hunt--Crossley).**  While the ball penetrates a wall by
  delta > 0,

      F = max(0, k delta^n (1 + chi delta' / v_in)),

  v_in the approach speed at the start of the contact episode (floored at
  ``v_floor``, so that a ball pressed slowly into a wall does not get an
  unbounded damping coefficient).  In scaled variables the contact depends on
  chi and n only, so the restitution of an isolated contact is independent of
  the speed, of k and of the masses; chi is **calibrated by root finding** so
  that it equals the material's e (:func:`solve_chi`), and the calibration
  is verified on isolated impacts in the full rig (:func:`isolated_impact`).
  Stiffness: steel walls Hertz (sphere on flat, E = 210 GPa, nu = 0.3;
  n = 3/2; contact ~0.1--0.3 ms at the rig's 0.05--0.2 m/s); linings a thin
  elastic layer on steel (Winkler, n = 2, k = pi R E_c / h_layer, with an
  assumed effective compression modulus E_c = 20 MPa -- not measured;
  contact ~2--10 ms).  All contacts are far shorter than the 667 ms forcing
  period, which is what matters for the comparison.  Not modelled: bottoming
  out of a lining (reported as ``max_penetration`` versus the thickness), wall
  friction and ball spin, speed dependence of e.
* **Sensor.**  The optical sensor's range (+-``range_mm``; values beyond are
  clipped at the limit), white noise (``noise_mm`` rms, the analysis'
  assumption 0.01 mm) and sample rate.  Only x is "measured"; the records also
  carry s (the ball centre's horizontal offset), which a real rig could not
  measure, for impact counting.
* **Drop tests** (:func:`drop_test_record`): the ball falls freely from 25, 50,
  100 cm (no air drag) onto the wall material with the same contact law and
  gravity acting during the contact; the struck body is a free mass M = m/mu
  (the reading of Eq. 3b the analysis uses) or rigid (``target: rigid``, then
  the header's mu is 0).

Integration: explicit Dormand--Prince 5(4) with error control, in numba
(:func:`_rig_run`).  Contact onsets are located (a step that would end deeper
than ``onset_tol`` in a wall is retried shorter), steps inside a contact are
capped at a tenth of the estimated contact duration, and every sample time is
a step end (no interpolation).  A full 500-period run with impacts costs tens
of milliseconds.

Units: the kernel works in SI (m, s, kg, N); records are written in mm.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
from numba import njit
from scipy import integrate, optimize

from impact.engine.jitcache import compile_lock
from impact.model.kinds import PID
from impact.outputs.measurements import Measurement, make_measurement
from impact.rig.config import validation_config

G_STANDARD = 9.80665
RIG_SOURCE = "virtual rig (impact.rig.simulator): synthetic, simulated -- not measured data"

def merged_config(cfg: dict | None) -> dict[str, Any]:
    """``cfg`` with every default filled in from the rig's schema (:mod:`.grid`, ``rig.schema.yaml``)."""
    return validation_config(cfg)


# ----------------------------------------------------------------------------
# contact law: calibration of the Hunt-Crossley damping
# ----------------------------------------------------------------------------


def _scaled_contact(chi: float, n: float) -> tuple[float, float, float]:
    """Isolated contact in scaled variables: u'' = -max(0, u^n (1 + chi u')), u(0) = 0, u'(0) = 1.

    (u = delta / delta_s, time in t_s with m_r delta_s / t_s^2 = k delta_s^n and
    delta_s / t_s = v_in, so mass, stiffness and speed drop out.)  Returns
    (restitution, contact duration, max penetration) in scaled units.
    """

    def rhs(_t, y):
        u, w = y
        f = max(u, 0.0) ** n * (1.0 + chi * w)
        return [w, -max(f, 0.0)]

    def back(_t, y):
        return y[0]

    back.terminal = True
    back.direction = -1
    # duration: for chi = 0, tau = 2 int_0^umax du / sqrt(1 - 2 u^(n+1)/(n+1)); generous bound
    sol = integrate.solve_ivp(rhs, (0.0, 200.0), [0.0, 1.0], method="DOP853", rtol=1e-12, atol=1e-14,
                              events=back, dense_output=False, max_step=0.01)
    if not sol.t_events[0].size:
        raise RuntimeError(f"contact with chi={chi} n={n} did not end")
    w_end = sol.y_events[0][0][1]
    return float(-w_end), float(sol.t_events[0][0]), float(np.max(sol.y[0]))


@functools.lru_cache(maxsize=64)
def solve_chi(e: float, n: float) -> float:
    """Hunt--Crossley damping chi giving restitution e for F = k delta^n (1 + chi delta'/v_in).

    Root of e_eff(chi) = e by Brent's method on the scaled isolated contact
    (:func:`_scaled_contact`); chi = 0 for e = 1.  For comparison, Hunt and
    Crossley's own small-damping estimate is chi = 3 (1 - e) / 2, which is
    accurate only for e close to 1.
    """
    if not 0.0 < e <= 1.0:
        raise ValueError(f"e = {e!r}: the rig needs 0 < e <= 1")
    if e == 1.0:
        return 0.0
    f = lambda chi: _scaled_contact(chi, n)[0] - e  # noqa: E731
    hi = 1.0
    while f(hi) > 0.0:
        hi *= 2.0
        if hi > 1e6:
            raise RuntimeError("cannot bracket chi")
    return float(optimize.brentq(f, 0.0, hi, xtol=1e-13, rtol=1e-12))


def scaled_restitution(chi: float, n: float) -> float:
    """Restitution of an isolated contact with damping chi and exponent n."""
    return _scaled_contact(chi, n)[0]


# ----------------------------------------------------------------------------
# the rig's physical parameters
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Wall:
    """A wall material: restitution e and contact law F = k delta^n (1 + chi delta'/v_in)."""

    name: str
    e: float
    k: float          # N / m^n
    n: float
    chi: float
    thickness_m: float = math.inf   # lining thickness (inf: bare steel)


def _wall_law(cfg: dict, spec: dict, ball_radius_m: float) -> tuple[float, float, float]:
    """(k, n, lining thickness) of a wall's contact law for a ball of radius ``ball_radius_m`` (SI)."""
    law = spec.get("law", "hertz")
    if law == "hertz":
        eb, nb = float(cfg["balls"]["youngs_modulus_pa"]), float(cfg["balls"]["poisson"])
        ew, nw = float(spec["youngs_modulus_pa"]), float(spec["poisson"])
        e_star = 1.0 / ((1 - nb**2) / eb + (1 - nw**2) / ew)
        return 4.0 / 3.0 * e_star * math.sqrt(ball_radius_m), 1.5, math.inf
    if law == "layer":
        thick = float(spec["thickness_mm"]) * 1e-3
        return math.pi * ball_radius_m * float(spec["layer_modulus_pa"]) / thick, 2.0, thick
    if law == "power":
        return float(spec["k"]), float(spec["n"]), math.inf
    raise ValueError(f"unknown contact law {law!r} (hertz, layer, power)")


def wall_contact(cfg: dict, wall: str, ball_radius_m: float) -> Wall:
    """The contact law of ``wall`` for a ball of radius ``ball_radius_m`` (SI), chi calibrated."""
    spec = cfg["walls"][wall]
    e = float(spec["e"])
    try:
        k, n, thick = _wall_law(cfg, spec, ball_radius_m)
    except ValueError as err:
        raise ValueError(f"wall {wall}: {err}") from None
    scale = float(cfg["contact"].get("stiffness_scale", 1.0))
    chi = float(spec["chi"]) if "chi" in spec else solve_chi(e, n)  # calibrated earlier (with_calibrations)
    return Wall(wall, e, k * scale, n, chi, thick)


def contact_calibrations(cfg: dict | None = None) -> list[dict]:
    """chi of every wall of the configuration: one calibration that all of the rig's runs can share.

    The exponent n does not depend on the ball, so one chi serves every ball against a wall.
    """
    cfg = merged_config(cfg)
    out = []
    for wall, spec in cfg["walls"].items():
        e, n = float(spec["e"]), _wall_law(cfg, spec, 1.0)[1]
        out.append({"wall": wall, "e": e, "n": n, "chi": solve_chi(e, n)})
    return out


def with_calibrations(cfg: dict | None, entries) -> dict:
    """``cfg`` (defaults filled in) with each wall's chi from an earlier :func:`contact_calibrations`, so that
    the rig does not solve for it again.  An entry whose e and n no longer match its wall's is not used."""
    cfg = merged_config(cfg)
    walls = {wall: dict(spec) for wall, spec in cfg["walls"].items()}
    for item in entries:
        spec = walls.get(item["wall"])
        if spec is not None and (float(spec["e"]), _wall_law(cfg, spec, 1.0)[1]) == (item["e"], item["n"]):
            spec["chi"] = float(item["chi"])
    return {**cfg, "walls": walls}


def pendulum_length(rp: float, omega: float, ball_radius_m: float, g: float = G_STANDARD,
                    rule: str = "compound") -> float:
    """Hook-to-centre length L of the pendulum for tuning ratio r'.

    'compound': the small-angle frequency of the ball on the string (rigid
    compound pendulum, I_c = 2/5 m a^2), sqrt(g L / (L^2 + 2/5 a^2)), equals
    r' omega; 'point_mass': L = g / (r' omega)^2.
    """
    lp = g / (rp * omega) ** 2
    if rule == "point_mass" or ball_radius_m == 0.0:
        return lp
    if rule != "compound":
        raise ValueError(f"length_rule {rule!r} is not 'compound' or 'point_mass'")
    k2 = 0.4 * ball_radius_m**2
    disc = lp * lp - 4.0 * k2
    if disc <= 0:
        raise ValueError("ball too large for this pendulum frequency")
    return 0.5 * (lp + math.sqrt(disc))


@dataclass(frozen=True)
class RigSpec:
    """One configuration of the virtual rig, SI units.

    ``m = 0`` is the bare structure (no ball).  ``rp``, ``mu``, ``gap_mm``,
    ``wall``, ``ball_diameter_mm`` are kept for the record headers.
    """

    structure_hz: float
    beta: float
    M: float
    m: float
    ball_radius: float
    L: float
    I_c: float
    g: float
    force: float          # F0 [N]
    phase: float
    half_gap: float       # d/2 [m]
    wall: Wall | None
    v_floor: float
    nonlinear: bool
    sensor: bool
    range_m: float
    noise_m: float
    sample_rate_hz: float
    rtol: float
    atol_m: float
    onset_tol_m: float
    mu: float
    rp: float
    gap_mm: float
    ball_diameter_mm: float
    force_ratio_mm: float

    @property
    def omega(self) -> float:
        return 2.0 * math.pi * self.structure_hz

    @property
    def K(self) -> float:
        return self.M * self.omega**2

    @property
    def C(self) -> float:
        return 2.0 * self.beta * self.M * self.omega

    @property
    def pendulum_hz(self) -> float:
        """Small-angle frequency of the pendulum with the structure held."""
        if self.m == 0.0:
            return math.nan
        return math.sqrt(self.m * self.g * self.L / (self.m * self.L**2 + self.I_c)) / (2.0 * math.pi)

    @property
    def a_max_mm(self) -> float:
        return self.force_ratio_mm / (2.0 * self.beta)

    def as_dict(self) -> dict:
        return asdict(self)


def ball_mass(cfg: dict, mu: float, diameter_mm: float) -> float:
    """Ball mass [kg]: mu * M ('mass_from: mu') or rho * pi D^3 / 6 ('density')."""
    if cfg["balls"].get("mass_from", "mu") == "density":
        return cfg["balls"]["density_kg_m3"] * math.pi * (diameter_mm * 1e-3) ** 3 / 6.0
    return mu * cfg["structure"]["mass_kg"]


def diameter_for_mu(cfg: dict, mu: float) -> float:
    """The ball diameter [mm] the configuration pairs with mass ratio mu."""
    mus = list(cfg["balls"]["mu"])
    for m_, d_ in zip(mus, cfg["balls"]["diameters_mm"]):
        if abs(m_ - mu) <= 1e-9 * max(1.0, mu):
            return float(d_)
    raise ValueError(f"mu = {mu!r} is not one of the configured balls {mus}")


def rig_spec(cfg: dict | None = None, *, mu: float | None = None, gap_mm: float | None = None,
             rp: float | None = None, wall: str | None = None, bare: bool = False,
             **fidelity: Any) -> RigSpec:
    """The rig for one case (``bare=True``: the structure without the ball).

    ``fidelity`` overrides ``cfg['fidelity']`` (nonlinear_pendulum,
    finite_radius, sensor) and may also give ``stiffness_scale`` and
    ``length_rule``.
    """
    cfg = merged_config(cfg)
    fid = {**cfg["fidelity"], **{k: v for k, v in fidelity.items() if k in cfg["fidelity"]}}
    unknown = set(fidelity) - set(cfg["fidelity"]) - {"stiffness_scale", "length_rule"}
    if unknown:
        raise ValueError(f"unknown fidelity switches {sorted(unknown)}")
    if "stiffness_scale" in fidelity:
        cfg["contact"]["stiffness_scale"] = fidelity["stiffness_scale"]
    rule = fidelity.get("length_rule", cfg["pendulum"].get("length_rule", "compound"))
    st = cfg["structure"]
    f = float(st["frequency_hz"])
    omega = 2.0 * math.pi * f
    big_m = float(st["mass_kg"])
    g = float(cfg["pendulum"].get("g", G_STANDARD))
    fr_mm = float(cfg["excitation"]["force_ratio_mm"])
    force = big_m * omega**2 * fr_mm * 1e-3
    sen = cfg["sensor"]
    integ = cfg["integrator"]
    common = dict(structure_hz=f, beta=float(st["beta"]), M=big_m, g=g, force=force,
                  phase=float(cfg["excitation"].get("phase", 0.0)),
                  v_floor=float(cfg["contact"]["v_floor_m_s"]), nonlinear=bool(fid["nonlinear_pendulum"]),
                  sensor=bool(fid["sensor"]), range_m=float(sen["range_mm"]) * 1e-3,
                  noise_m=float(sen["noise_mm"]) * 1e-3, sample_rate_hz=float(sen["sample_rate_hz"]),
                  rtol=float(integ["rtol"]), atol_m=float(integ["atol_m"]),
                  onset_tol_m=float(integ["onset_tol_m"]), force_ratio_mm=fr_mm)
    if bare:
        return RigSpec(m=0.0, ball_radius=0.0, L=1.0, I_c=0.0, half_gap=1.0, wall=None, mu=0.0, rp=0.0,
                       gap_mm=0.0, ball_diameter_mm=0.0, **common)
    if None in (mu, gap_mm, rp, wall):
        raise ValueError("give mu, gap_mm, rp and wall (or bare=True)")
    dia = diameter_for_mu(cfg, mu)
    a = 0.5 * dia * 1e-3
    m = ball_mass(cfg, mu, dia)
    if fid["finite_radius"]:
        L, ic = pendulum_length(rp, omega, a, g, rule), 0.4 * m * a * a
    else:
        L, ic = pendulum_length(rp, omega, 0.0, g, "point_mass"), 0.0
    w = wall_contact(cfg, wall, a)
    return RigSpec(m=m, ball_radius=a, L=L, I_c=ic, half_gap=0.5 * gap_mm * 1e-3, wall=w, mu=m / big_m,
                   rp=float(rp), gap_mm=float(gap_mm), ball_diameter_mm=dia, **common)


# ----------------------------------------------------------------------------
# numba kernel
# ----------------------------------------------------------------------------

# parameter vector layout
Q_M, Q_K, Q_C, Q_m, Q_L, Q_IC, Q_G, Q_F, Q_OM, Q_PHI = 0, 1, 2, 3, 4, 5, 6, 7, 8, 9
Q_KC, Q_N, Q_CHI, Q_H, Q_VF, Q_NL, Q_BALL, Q_RTOL, Q_ATOL, Q_HMAX = 10, 11, 12, 13, 14, 15, 16, 17, 18, 19
Q_ONSET, Q_HMAXSET = 20, 21
NQ = 22

# diagnostics layout
G_EPIS, G_STEPS, G_REJ, G_PEN, G_TEND, G_NEP, G_VIN, G_FAIL = 0, 1, 2, 3, 4, 5, 6, 7
NG = 8

# contact episode columns: onset t, side, approach speed (raw), exit t, exit speed (side * s', signed), max pen
NEPC = 6


@njit(cache=True)
def _penetration(z, q):
    """(penetration, side, s, s') of the ball into the nearer wall (penetration <= 0: free)."""
    L = q[Q_L]
    th = z[2]
    if q[Q_NL] > 0.5:
        s = L * math.sin(th)
        sd = L * math.cos(th) * z[3]
    else:
        s = L * th
        sd = L * z[3]
    h = q[Q_H]
    if s >= 0.0:
        return s - h, 1.0, s, sd
    return -s - h, -1.0, s, sd


@njit(cache=True)
def _rhs(t, z, q, vin, out):
    """Time derivative of (x, x', th, th') in SI units."""
    x = z[0]
    v = z[1]
    force = q[Q_F] * math.sin(q[Q_OM] * t + q[Q_PHI])
    if q[Q_BALL] < 0.5:
        out[0] = v
        out[1] = (force - q[Q_C] * v - q[Q_K] * x) / q[Q_M]
        out[2] = 0.0
        out[3] = 0.0
        return
    th = z[2]
    w = z[3]
    m = q[Q_m]
    L = q[Q_L]
    if q[Q_NL] > 0.5:
        sn = math.sin(th)
        cs = math.cos(th)
        cent = m * L * sn * w * w
    else:
        sn = th
        cs = 1.0
        cent = 0.0
    pen, side, s, sd = _penetration(z, q)
    fb = 0.0
    if pen > 0.0:
        dd = side * sd
        vi = vin
        if vi <= 0.0:
            vi = max(dd, q[Q_VF])
        f = q[Q_KC] * pen ** q[Q_N] * (1.0 + q[Q_CHI] * dd / vi)
        if f > 0.0:
            fb = -side * f
    a11 = q[Q_M] + m
    a12 = m * L * cs
    a22 = m * L * L + q[Q_IC]
    r1 = force - q[Q_C] * v - q[Q_K] * x + cent
    r2 = -m * q[Q_G] * L * sn + fb * L * cs
    det = a11 * a22 - a12 * a12
    out[0] = v
    out[1] = (a22 * r1 - a12 * r2) / det
    out[2] = w
    out[3] = (a11 * r2 - a12 * r1) / det


# Dormand-Prince 5(4) tableau
_C2, _C3, _C4, _C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
_A21 = 1.0 / 5.0
_A31, _A32 = 3.0 / 40.0, 9.0 / 40.0
_A41, _A42, _A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_A51, _A52, _A53, _A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_A61, _A62, _A63, _A64, _A65 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0
_B1, _B3, _B4, _B5, _B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
_E1, _E3, _E4, _E5, _E6, _E7 = (71.0 / 57600.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0,
                                22.0 / 525.0, -1.0 / 40.0)


@njit(cache=True)
def _dopri(t, z, h, q, vin, k, ytmp, znew, sc):
    """One Dormand-Prince step; writes znew, returns (scaled error norm, max stage penetration)."""
    _rhs(t, z, q, vin, k[0])
    pmax = -1e300
    for i in range(4):
        ytmp[i] = z[i] + h * _A21 * k[0, i]
    _rhs(t + _C2 * h, ytmp, q, vin, k[1])
    p = _penetration(ytmp, q)[0]
    pmax = max(pmax, p)
    for i in range(4):
        ytmp[i] = z[i] + h * (_A31 * k[0, i] + _A32 * k[1, i])
    _rhs(t + _C3 * h, ytmp, q, vin, k[2])
    pmax = max(pmax, _penetration(ytmp, q)[0])
    for i in range(4):
        ytmp[i] = z[i] + h * (_A41 * k[0, i] + _A42 * k[1, i] + _A43 * k[2, i])
    _rhs(t + _C4 * h, ytmp, q, vin, k[3])
    pmax = max(pmax, _penetration(ytmp, q)[0])
    for i in range(4):
        ytmp[i] = z[i] + h * (_A51 * k[0, i] + _A52 * k[1, i] + _A53 * k[2, i] + _A54 * k[3, i])
    _rhs(t + _C5 * h, ytmp, q, vin, k[4])
    pmax = max(pmax, _penetration(ytmp, q)[0])
    for i in range(4):
        ytmp[i] = z[i] + h * (_A61 * k[0, i] + _A62 * k[1, i] + _A63 * k[2, i] + _A64 * k[3, i]
                              + _A65 * k[4, i])
    _rhs(t + h, ytmp, q, vin, k[5])
    pmax = max(pmax, _penetration(ytmp, q)[0])
    for i in range(4):
        znew[i] = z[i] + h * (_B1 * k[0, i] + _B3 * k[2, i] + _B4 * k[3, i] + _B5 * k[4, i] + _B6 * k[5, i])
    _rhs(t + h, znew, q, vin, k[6])
    err = 0.0
    for i in range(4):
        ei = h * (_E1 * k[0, i] + _E3 * k[2, i] + _E4 * k[3, i] + _E5 * k[4, i] + _E6 * k[5, i] + _E7 * k[6, i])
        s = sc[i] + q[Q_RTOL] * max(abs(z[i]), abs(znew[i]))
        err += (ei / s) ** 2
    return math.sqrt(err / 4.0), pmax


@njit(cache=True)
def _contact_time(q, vin):
    """Rough duration of a contact entered at speed vin (to cap the step inside it)."""
    n = q[Q_N]
    m = q[Q_m]
    v = max(vin, q[Q_VF])
    dmax = ((n + 1.0) * m * v * v / (2.0 * q[Q_KC])) ** (1.0 / (n + 1.0))
    return 2.5 * dmax / v


@njit(cache=True)
def _rig_run(q, z0, t0, t_end, ts, xs, ss, eps, diag, zout):
    """Integrate the rig from t0 to t_end; sample x and s at the times ts (>= t0, sorted).

    q: parameters (Q_*); z0: (x, x', th, th'); eps: (n, NEPC) contact episodes
    (as many as fit); diag: NG diagnostics; zout: final state.
    """
    for i in range(NG):
        diag[i] = 0.0
    z = z0.copy()
    znew = np.empty(4)
    ytmp = np.empty(4)
    k = np.empty((7, 4))
    sc = np.empty(4)
    L = q[Q_L]
    om = q[Q_OM] if q[Q_OM] > 0.0 else 1.0
    wn = math.sqrt(q[Q_K] / q[Q_M])
    wref = max(om, wn)
    sc[0] = q[Q_ATOL]
    sc[1] = q[Q_ATOL] * wref
    sc[2] = q[Q_ATOL] / L
    sc[3] = q[Q_ATOL] * wref / L
    t = t0
    ns = ts.shape[0]
    isamp = 0
    while isamp < ns and ts[isamp] < t0 - 1e-12:
        isamp += 1
    # samples at t0
    while isamp < ns and abs(ts[isamp] - t) <= 1e-12:
        pen, side, s, sd = _penetration(z, q)
        xs[isamp] = z[0]
        ss[isamp] = s
        isamp += 1
    h = min(q[Q_HMAXSET], 1e-3)
    pen0, side0, s0, sd0 = _penetration(z, q)
    vin = 0.0
    in_contact = pen0 > 0.0
    if in_contact:
        vin = max(side0 * sd0, q[Q_VF])
    nep = eps.shape[0]
    iep = -1
    while t < t_end:
        hmax = q[Q_HMAXSET]
        if isamp < ns and t >= ts[0] - q[Q_HMAX]:
            hmax = q[Q_HMAX]  # inside the sampled window
        if in_contact and q[Q_BALL] > 0.5:
            hmax = min(hmax, 0.1 * _contact_time(q, vin))
        h = min(h, hmax)
        t_target = t_end
        if isamp < ns and ts[isamp] < t_target:
            t_target = ts[isamp]
        clipped = False
        if t + h >= t_target - 1e-13 * max(1.0, abs(t_target)):
            h = t_target - t
            clipped = True
        if h <= 0.0:
            # sample at the current time
            h = 1e-12
        err, pmax = _dopri(t, z, h, q, vin, k, ytmp, znew, sc)
        diag[G_STEPS] += 1.0
        if not (err <= 1.0) or not math.isfinite(err):
            diag[G_REJ] += 1.0
            fac = 0.2 if not math.isfinite(err) else max(0.2, 0.9 * err ** -0.2)
            h = h * fac
            if h < 1e-15:
                diag[G_FAIL] = 1.0
                break
            continue
        pen1, side1, s1, sd1 = _penetration(znew, q)
        if q[Q_BALL] > 0.5 and not in_contact:
            pen_start = _penetration(z, q)[0]
            worst = max(pen1, pmax)
            if worst > q[Q_ONSET] and h > 1e-13:
                # the step would enter a wall deeper than the onset tolerance: land at the onset
                if pen1 > q[Q_ONSET]:
                    frac = -pen_start / (pen1 - pen_start)
                    hn = h * frac + 0.5 * q[Q_ONSET] * h / (pen1 - pen_start)
                    if hn >= h:
                        hn = 0.5 * h
                else:
                    hn = 0.5 * h  # touched the wall inside the step only
                h = max(hn, 1e-14)
                diag[G_REJ] += 1.0
                continue
        # accept
        t = t + h if not clipped else t_target
        for i in range(4):
            z[i] = znew[i]
        if q[Q_BALL] > 0.5:
            if not in_contact and pen1 > 0.0:
                in_contact = True
                vraw = side1 * sd1
                vin = max(vraw, q[Q_VF])
                diag[G_EPIS] += 1.0
                iep += 1
                if iep < nep:
                    eps[iep, 0] = t
                    eps[iep, 1] = side1
                    eps[iep, 2] = vraw
                    eps[iep, 3] = np.nan
                    eps[iep, 4] = np.nan
                    eps[iep, 5] = pen1
            elif in_contact:
                if pen1 > 0.0:
                    if iep >= 0 and iep < nep and pen1 > eps[iep, 5]:
                        eps[iep, 5] = pen1
                else:
                    in_contact = False
                    vin = 0.0
                    if iep >= 0 and iep < nep:
                        eps[iep, 3] = t
                        eps[iep, 4] = eps[iep, 1] * sd1
            if pen1 > diag[G_PEN]:
                diag[G_PEN] = pen1
        while isamp < ns and ts[isamp] <= t + 1e-12:
            pen, side, s, sd = _penetration(z, q)
            xs[isamp] = z[0]
            ss[isamp] = s
            isamp += 1
        fac = 5.0 if err == 0.0 else min(5.0, max(0.2, 0.9 * err ** -0.2))
        h = h * fac
    diag[G_TEND] = t
    diag[G_NEP] = min(iep + 1, nep)
    diag[G_VIN] = vin
    for i in range(4):
        zout[i] = z[i]


def param_vector(spec: RigSpec, r: float, *, forced: bool = True) -> np.ndarray:
    """The kernel's parameter vector for frequency ratio r (forced=False: no force)."""
    q = np.zeros(NQ)
    q[Q_M], q[Q_K], q[Q_C] = spec.M, spec.K, spec.C
    q[Q_m], q[Q_L], q[Q_IC], q[Q_G] = spec.m, spec.L, spec.I_c, spec.g
    q[Q_F] = spec.force if forced else 0.0
    q[Q_OM] = r * spec.omega
    q[Q_PHI] = spec.phase
    w = spec.wall
    if w is not None and spec.m > 0:
        q[Q_KC], q[Q_N], q[Q_CHI] = w.k, w.n, w.chi
        q[Q_BALL] = 1.0
    else:
        q[Q_KC], q[Q_N], q[Q_CHI] = 1.0, 1.5, 0.0
    q[Q_H] = spec.half_gap
    q[Q_VF] = spec.v_floor
    q[Q_NL] = 1.0 if spec.nonlinear else 0.0
    q[Q_RTOL], q[Q_ATOL] = spec.rtol, spec.atol_m
    q[Q_HMAX] = 1.0 / spec.sample_rate_hz
    q[Q_HMAXSET] = 1.0 / (20.0 * spec.structure_hz)
    q[Q_ONSET] = spec.onset_tol_m
    return q


@dataclass
class RigRun:
    """A raw rig run: true (noise-free) samples in SI units and the contact episodes."""

    t: np.ndarray          # s
    x: np.ndarray          # m, true structure displacement
    s: np.ndarray          # m, ball centre's horizontal offset from the hook
    episodes: np.ndarray   # (n, NEPC): onset t, side, approach speed, exit t, exit speed, max pen
    n_episodes: int
    steps: int
    rejected: int
    max_penetration: float
    final_state: np.ndarray
    failed: bool


def run(spec: RigSpec, r: float, t_end: float, sample_times, *, state=None, t0: float = 0.0,
        forced: bool = True, max_episodes: int = 100000) -> RigRun:
    """Integrate the rig from ``state`` (default rest) at t0 to t_end; sample at ``sample_times`` [s]."""
    q = param_vector(spec, r, forced=forced)
    z0 = np.zeros(4) if state is None else np.asarray(state, dtype=float).copy()
    ts = np.ascontiguousarray(sample_times, dtype=float)
    xs = np.full(ts.size, np.nan)
    ss = np.full(ts.size, np.nan)
    eps = np.zeros((max_episodes, NEPC))
    diag = np.zeros(NG)
    zout = np.zeros(4)
    _rig_run(q, z0, float(t0), float(t_end), ts, xs, ss, eps, diag, zout)
    n = int(diag[G_NEP])
    return RigRun(t=ts, x=xs, s=ss, episodes=eps[:n].copy(), n_episodes=int(diag[G_EPIS]),
                  steps=int(diag[G_STEPS]), rejected=int(diag[G_REJ]), max_penetration=float(diag[G_PEN]),
                  final_state=zout, failed=bool(diag[G_FAIL]))


def theta_for_offset(spec: RigSpec, s_m: float) -> float:
    """Pendulum angle giving the horizontal offset s (m)."""
    return math.asin(s_m / spec.L) if spec.nonlinear else s_m / spec.L


def energy(spec: RigSpec, z, t_wall_pen: float | None = None) -> float:
    """Mechanical energy of the rig state z = (x, x', th, th') [J], contact potential included."""
    x, v, th, w = (float(c) for c in z)
    m, L = spec.m, spec.L
    if spec.nonlinear:
        kin = 0.5 * (spec.M + m) * v * v + m * L * math.cos(th) * v * w + 0.5 * (m * L * L + spec.I_c) * w * w
        pot = 0.5 * spec.K * x * x + m * spec.g * L * (1.0 - math.cos(th))
        s = L * math.sin(th)
    else:
        kin = 0.5 * (spec.M + m) * v * v + m * L * v * w + 0.5 * (m * L * L + spec.I_c) * w * w
        pot = 0.5 * spec.K * x * x + 0.5 * m * spec.g * L * th * th
        s = L * th
    pen = abs(s) - spec.half_gap
    if pen > 0 and spec.wall is not None and m > 0:
        pot += spec.wall.k * pen ** (spec.wall.n + 1.0) / (spec.wall.n + 1.0)
    return kin + pot


_WARM = False


def warm_up() -> None:
    """Compile (or load from numba's on-disk cache) the rig kernels.

    Under the same exclusive file lock as :func:`impact.engine.paper.ensure_compiled`,
    so that processes starting together never write the cache at once.
    """
    global _WARM
    if _WARM:
        return
    with compile_lock("rig", "the virtual test rig's kernels"):
        spec = rig_spec(mu=0.0129, gap_mm=30.0, rp=1.0, wall="steel")
        run(spec, 1.0, 0.05, np.array([0.0, 0.01]), state=[0.0, 0.0, 0.3, 0.0], max_episodes=1)
        _drop_contact(0.1, 1.0, 1e9, 1.5, 0.5, 1e-3, 1.0, 9.8, 0.0)
    _WARM = True


# ----------------------------------------------------------------------------
# sensor and records
# ----------------------------------------------------------------------------


def sensor_reading(spec: RigSpec, x_m: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The optical sensor: true x plus white noise, clipped to +-range (SI in, SI out)."""
    if not spec.sensor:
        return np.asarray(x_m, dtype=float).copy()
    y = np.asarray(x_m, dtype=float) + spec.noise_m * rng.standard_normal(np.shape(x_m))
    return np.clip(y, -spec.range_m, spec.range_m)


def _header_common(spec: RigSpec, kind: str, seed: int, *, wall_name: str | None, notes: str) -> dict:
    hdr: dict[str, Any] = {
        "format_version": 1,
        "kind": kind,
        "synthetic": True,
        "sample_rate_hz": spec.sample_rate_hz,
        "units": "mm",
        "damper": "none" if spec.m == 0.0 else PID,
        "structure_hz": spec.structure_hz,
        "noise_rms": spec.noise_m * 1e3 if spec.sensor else 0.0,
        "seed": int(seed),
        "source": RIG_SOURCE,
    }
    if spec.m > 0.0:
        hdr.update(mu=spec.mu, gap_mm=spec.gap_mm, rp=spec.rp, e=spec.wall.e,
                   ball_diameter_mm=spec.ball_diameter_mm)
        if wall_name:
            hdr["wall"] = wall_name
    hdr["notes"] = notes
    return hdr


def describe(spec: RigSpec) -> str:
    """One-line summary of the rig's fidelity settings (goes into the record notes)."""
    parts = [f"M={spec.M:g} kg", f"beta={spec.beta:g}", f"F0/K={spec.force_ratio_mm:g} mm"]
    if spec.m > 0:
        parts += [f"m={spec.m:.4g} kg", f"L={spec.L * 1e3:.2f} mm", f"I_c={spec.I_c:.3g} kg m2",
                  f"pendulum {'nonlinear' if spec.nonlinear else 'linearised'}",
                  f"contact k={spec.wall.k:.3g} n={spec.wall.n:g} chi={spec.wall.chi:.4g}"]
    if spec.sensor:
        parts.append(f"sensor +-{spec.range_m * 1e3:g} mm, noise {spec.noise_m * 1e3:g} mm rms")
    else:
        parts.append("sensor ideal")
    return "virtual rig; " + "; ".join(parts)


def seed_for(*parts: Any, base: int = 0) -> int:
    """A deterministic seed from the case description (stable across runs and processes)."""
    text = "|".join(repr(p) for p in parts)
    h = 0
    for ch in text.encode():
        h = (h * 1000003 + ch) % (2**61 - 1)
    return int((h + int(base)) % (2**31 - 1))


@dataclass
class RigOutput:
    """A record and the rig's internals behind it (true x, contact episodes)."""

    record: Measurement
    raw: RigRun


def forced_point(spec: RigSpec, r: float, *, periods: float = 500, average_from: float = 250,
                 seed: int = 0, wall_name: str | None = None, state=None) -> RigOutput:
    """One ``forced_sweep_point`` record: run from rest (or ``state``) for ``periods``
    natural periods of the structure and record the window from ``average_from`` on
    (the paper's protocol, Sect. 4)."""
    T = 1.0 / spec.structure_hz
    fs = spec.sample_rate_hz
    t_win, t_end = average_from * T, periods * T
    n0 = int(math.ceil(t_win * fs - 1e-9))
    n1 = int(math.floor(t_end * fs - 1e-9))
    ts = np.arange(n0, n1 + 1) / fs
    raw = run(spec, r, t_end, ts, state=state)
    if raw.failed or not np.all(np.isfinite(raw.x)):
        raise RuntimeError(f"rig integration failed at r={r}")
    rng = np.random.default_rng(seed)
    xm = sensor_reading(spec, raw.x, rng)
    hdr = _header_common(spec, "forced_sweep_point", seed, wall_name=wall_name,
                         notes=describe(spec) + f"; from rest, {periods:g} periods, window from {average_from:g}")
    hdr["r"] = float(r)
    hdr["forcing_hz"] = float(r) * spec.structure_hz
    cols = {"t_s": ts, "x": xm * 1e3}
    if spec.m > 0:
        cols["s"] = raw.s * 1e3
    return RigOutput(make_measurement(hdr, cols), raw)


def free_decay(spec: RigSpec, x0_mm: float, *, duration_s: float = 60.0, seed: int = 0,
               wall_name: str | None = None) -> RigOutput:
    """One ``free_decay`` record: structure held at x0 with the ball hanging at rest, released at t = 0."""
    fs = spec.sample_rate_hz
    ts = np.arange(int(math.floor(duration_s * fs)) + 1) / fs
    raw = run(spec, 1.0, ts[-1], ts, state=[x0_mm * 1e-3, 0.0, 0.0, 0.0], forced=False)
    if raw.failed or not np.all(np.isfinite(raw.x)):
        raise RuntimeError("rig integration failed in a free decay")
    rng = np.random.default_rng(seed)
    xm = sensor_reading(spec, raw.x, rng)
    hdr = _header_common(spec, "free_decay", seed, wall_name=wall_name,
                         notes=describe(spec) + "; released from rest, ball hanging")
    hdr["x0_mm"] = float(x0_mm)
    cols = {"t_s": ts, "x": xm * 1e3}
    if spec.m > 0:
        cols["s"] = raw.s * 1e3
    return RigOutput(make_measurement(hdr, cols), raw)


# ----------------------------------------------------------------------------
# isolated impacts (calibration check)
# ----------------------------------------------------------------------------


def isolated_impact(spec: RigSpec, approach_m_s: float, side: int = 1, *, external: bool = False) -> dict:
    """One impact of the ball on a wall in the full rig, structure initially at rest.

    The ball starts 0.1 mm from the wall (the pendulum deflected to s = +-(d/2 -
    0.1 mm)) moving at ``approach_m_s`` relative to the structure.  By default
    the impact is isolated: no gravity, no structural spring, damping or
    force, so that only the contact law and the rig's geometry and inertia
    (cos theta lever, ball rotation, the structure's recoil) act -- the
    situation the calibration of chi assumes.  ``external=True`` keeps gravity
    and the spring: their impulse during the contact then adds to the rebound
    (a compliance effect, measured separately).  Returns the effective
    restitution -(s'_exit / s'_onset) from the relative velocities at the
    contact's start and end, the contact duration and the largest penetration.
    """
    sp = replace(spec, beta=0.0, sensor=False)
    s0 = side * (spec.half_gap - 1e-4)
    th0 = theta_for_offset(sp, s0)
    cs = math.cos(th0) if sp.nonlinear else 1.0
    # relative velocity of the ball s' = L cos th th', with the structure at rest
    w0 = side * approach_m_s / (sp.L * cs)
    t_travel = 1e-4 / approach_m_s
    tc = _estimate_tc(sp, approach_m_s)
    q = param_vector(sp, 1.0, forced=False)
    if not external:
        q[Q_K] = 0.0
        q[Q_G] = 0.0
    eps = np.zeros((8, NEPC))
    diag = np.zeros(NG)
    zout = np.zeros(4)
    _rig_run(q, np.array([0.0, 0.0, th0, w0]), 0.0, t_travel + 20.0 * tc, np.array([0.0]), np.zeros(1),
             np.zeros(1), eps, diag, zout)
    if diag[G_NEP] < 1 or not np.isfinite(eps[0, 4]):
        raise RuntimeError("isolated impact: no complete contact")
    ep = eps[0]
    return {"e": float(-ep[4] / ep[2]), "contact_time_s": float(ep[3] - ep[0]),
            "max_penetration_m": float(ep[5]), "approach_m_s": float(ep[2])}


def _estimate_tc(spec: RigSpec, v: float) -> float:
    w = spec.wall
    n = w.n
    m_eff = spec.m
    dmax = ((n + 1.0) * m_eff * v * v / (2.0 * w.k)) ** (1.0 / (n + 1.0))
    return 3.0 * dmax / v


# ----------------------------------------------------------------------------
# drop tests
# ----------------------------------------------------------------------------


@njit(cache=True)
def _drop_contact(m, m_target, k, n, chi, v_floor, v0, g, rigid):
    """Ball (mass m, falling at v0 > 0) on a target (free mass m_target at rest, or rigid).

    Coordinates upward; contact from the touch until the penetration returns to
    zero; gravity acts on the ball (the target's weight is carried by its
    support).  Fixed-step RK4 with 4000 steps per estimated contact duration;
    the exit is interpolated linearly.  Returns (ball velocity after, target
    displacement at exit, contact duration, max penetration).
    """
    dmax = ((n + 1.0) * m * v0 * v0 / (2.0 * k)) ** (1.0 / (n + 1.0))
    tc = 3.0 * dmax / v0
    h = tc / 4000.0
    yb = 0.0
    vb = -v0
    yt = 0.0
    vt = 0.0
    vin = max(v0, v_floor)
    t = 0.0
    pmax = 0.0
    z = np.array([yb, vb, yt, vt])
    kk = np.empty((4, 4))
    tmp = np.empty(4)
    for it in range(10 ** 8):
        for st in range(4):
            if st == 0:
                for i in range(4):
                    tmp[i] = z[i]
            elif st < 3:
                for i in range(4):
                    tmp[i] = z[i] + 0.5 * h * kk[st - 1, i]
            else:
                for i in range(4):
                    tmp[i] = z[i] + h * kk[2, i]
            pen = tmp[2] - tmp[0]
            f = 0.0
            if pen > 0.0:
                dd = tmp[3] - tmp[1]
                f = k * pen ** n * (1.0 + chi * dd / vin)
                if f < 0.0:
                    f = 0.0
            kk[st, 0] = tmp[1]
            kk[st, 1] = f / m - g
            kk[st, 2] = tmp[3]
            kk[st, 3] = 0.0 if rigid > 0.5 else -f / m_target
        znew = z + h / 6.0 * (kk[0] + 2.0 * kk[1] + 2.0 * kk[2] + kk[3])
        pen_old = z[2] - z[0]
        pen_new = znew[2] - znew[0]
        t += h
        if pen_new > pmax:
            pmax = pen_new
        if it > 10 and pen_new <= 0.0:
            frac = pen_old / (pen_old - pen_new)
            vb_exit = z[1] + frac * (znew[1] - z[1])
            yt_exit = z[2] + frac * (znew[2] - z[2])
            return vb_exit, yt_exit, t - (1.0 - frac) * h, pmax
        z = znew
    return np.nan, np.nan, np.nan, pmax


def drop(cfg: dict | None, wall: str, mu: float, height_cm: float, *, target: str | None = None) -> dict:
    """One drop of the ball (mass ratio mu) from ``height_cm`` onto ``wall``: rebound height etc."""
    cfg = merged_config(cfg)
    target = target or cfg["drop_test"].get("target", "structure")
    dia = diameter_for_mu(cfg, mu)
    a = 0.5 * dia * 1e-3
    m = ball_mass(cfg, mu, dia)
    w = wall_contact(cfg, wall, a)
    g = float(cfg["pendulum"].get("g", G_STANDARD))
    v0 = math.sqrt(2.0 * g * height_cm * 1e-2)
    m_target = cfg["structure"]["mass_kg"]
    rigid = target == "rigid"
    if target not in ("structure", "rigid"):
        raise ValueError(f"drop_test target {target!r} is not 'structure' or 'rigid'")
    vb, yt, tc, pen = _drop_contact(m, m_target, w.k, w.n, w.chi, float(cfg["contact"]["v_floor_m_s"]),
                                    v0, g, 1.0 if rigid else 0.0)
    if not np.isfinite(vb) or vb <= 0:
        raise RuntimeError(f"drop test: no rebound (v = {vb})")
    rebound = max(yt + vb * vb / (2.0 * g), 0.0)
    return {"rebound_height_cm": rebound * 1e2, "contact_time_s": tc, "max_penetration_m": pen,
            "mu_header": 0.0 if rigid else m / m_target, "impact_speed_m_s": v0, "wall": w}


def drop_test_record(cfg: dict | None, wall: str, mu: float, *, heights_cm=None, repeats: int = 1,
                     seed: int = 0, target: str | None = None) -> Measurement:
    """A synthetic ``drop_test`` record: the ball of mass ratio mu dropped on ``wall``.

    One row per drop (``heights_cm`` x ``repeats``); rebound heights from
    :func:`drop`, plus the configured reading noise.  The header's ``mu`` is
    m/M for a free target (``target: structure``) and 0 for a rigid one, so
    that :func:`impact.outputs.signals.drop_test_restitution` applies
    Eq. (3b) consistently.  Penetrations beyond a lining's thickness (it would
    bottom out on the steel, which the rig does not model) are noted.
    """
    cfg = merged_config(cfg)
    heights = list(heights_cm if heights_cm is not None else cfg["drop_test"]["heights_cm"])
    noise = float(cfg["drop_test"].get("height_noise_cm", 0.0))
    rng = np.random.default_rng(seed)
    hd, hr, warn = [], [], []
    mu_hdr = None
    w = None
    for h in heights:
        res = drop(cfg, wall, mu, h, target=target)
        w = res["wall"]
        mu_hdr = res["mu_header"]
        if res["max_penetration_m"] > w.thickness_m:
            warn.append(f"{h:g} cm: penetration {res['max_penetration_m'] * 1e3:.2f} mm exceeds the "
                        f"{w.thickness_m * 1e3:g} mm lining (bottoming out not modelled)")
        for _ in range(repeats):
            rb = res["rebound_height_cm"] + (noise * rng.standard_normal() if noise > 0 else 0.0)
            hd.append(float(h))
            hr.append(float(min(max(rb, 0.0), h)))
    notes = (f"virtual rig drop test: ball D={diameter_for_mu(cfg, mu):g} mm on {wall}, free fall without "
             f"drag, Hunt-Crossley contact k={w.k:.3g} n={w.n:g} chi={w.chi:.4g}, target "
             f"{target or cfg['drop_test'].get('target', 'structure')}, height noise {noise:g} cm")
    if warn:
        notes += "; " + "; ".join(warn)
    hdr = {"format_version": 1, "kind": "drop_test", "synthetic": True, "mu": mu_hdr, "wall": wall,
           "e": w.e, "ball_diameter_mm": diameter_for_mu(cfg, mu), "seed": int(seed), "source": RIG_SOURCE,
           "notes": notes}
    return make_measurement(hdr, {"drop_height_cm": hd, "rebound_height_cm": hr})
