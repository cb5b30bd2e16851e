"""The pieces the four baseline integrators share (see the package's doc for the model).

The result record, the impact law, the start state, the affine form of every
smooth phase (``z' = A z + c + F sin(r t + phase)`` with a constant Jacobian
``A``), the affine functionals used as event and contact-force functions, and
the stuck phase, which the event-driven and the penalty integrators both run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from impact.model.params import STARTS, System

#: default relative velocity (in units of force_ratio * omega) below which a
#: rebound is merged into sustained contact (e = 0, end of a chatter sequence)
V_STICK = 1e-7


@dataclass
class BaselineResult:
    """What every baseline returns (model units).

    impact_times
        times of the impacts (ivp / rk4: located events; moreau: the end of a step in which a wall impulse was
        applied; penalty: contact entry)
    impact_side
        +1 right wall (s = +d/2), -1 left wall
    pre, post
        (n, 2) arrays of (x', y') just before / after each impact; penalty: at contact entry / exit (NaN post if the
        run ends in contact); moreau: at the start / end of the impulse step
    t_end
        time reached (the requested t_end unless the run failed)
    final_state
        (x, x', y, y') at t_end
    amplitude
        sqrt(2) * RMS of x over [t_window, t_end] (NaN if the run failed)
    n_impacts_window
        impacts with t >= t_window
    nfev
        right-hand-side (smooth force) evaluations
    n_steps
        accepted integration steps
    max_penetration
        largest abs(s) - d/2 seen at step points (negative: the walls were never reached)
    status
        'ok' or 'failed: <reason>'
    method
        short name of the method and its main setting
    """

    impact_times: np.ndarray
    impact_side: np.ndarray
    pre: np.ndarray
    post: np.ndarray
    t_end: float
    final_state: np.ndarray
    amplitude: float
    n_impacts_window: int
    nfev: int
    n_steps: int
    max_penetration: float
    status: str
    method: str = ""

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def n_impacts(self) -> int:
        return int(len(self.impact_times))


def impact_law(mu: float, e: float, xd: float, yd: float) -> tuple[float, float]:
    """Eq. 3: velocities (x', y') after an impact; conserves x' + mu y', s'+ = -e s'-."""
    k = 1.0 / (1.0 + mu)
    return ((1.0 - mu * e) * xd + mu * (1.0 + e) * yd) * k, ((1.0 + e) * xd + (mu - e) * yd) * k


def merged_velocity(mu: float, xd: float, yd: float) -> float:
    """Common velocity of a plastic (e = 0) merge, momentum-conserving."""
    return (xd + mu * yd) / (1.0 + mu)


def check_inputs(system: System, r: float, t_end: float, t_window: float, start: str) -> None:
    if not isinstance(system, System):
        raise TypeError("system must be an impact.model.params.System")
    if not (math.isfinite(r) and r > 0.0):
        raise ValueError(f"r = {r!r} must be a positive finite frequency ratio")
    if not (math.isfinite(t_end) and t_end > 0.0):
        raise ValueError(f"t_end = {t_end!r} must be positive and finite")
    if not (0.0 <= t_window < t_end):
        raise ValueError(f"t_window = {t_window!r} must lie in [0, t_end)")
    if start not in STARTS:
        raise ValueError(f"start = {start!r} is not allowed: choose one of {', '.join(STARTS)}")


def initial_state(system: System, start: str) -> tuple[np.ndarray, int]:
    """Rest state and the wall the damper mass touches (0: centred)."""
    if start == "centre" or system.gap == 0.0:
        return np.zeros(4), 0
    side = 1 if start == "right" else -1
    return np.array([0.0, 0.0, side * 0.5 * system.gap, 0.0]), side


#: default flight height (relative to |x| + d/2) below which a rebound is merged: a flight
#: that low is below the position resolution of integrators that carry x and y separately
H_STICK = 1e-10


def default_v_stick(system: System, v_stick) -> float:
    return V_STICK * system.force_ratio if v_stick is None else float(v_stick)


def rebound_negligible(system: System, r: float, t: float, z, side: int, v_stick: float,
                       h_stick: float = H_STICK) -> bool:
    """Is the rebound (post-impact state z at wall `side`) too slow or too low to resolve?

    True if |s'| < v_stick, or if the relative acceleration drives the mass back to
    the wall and the flight height s'^2 / (2 |s''|) is below h_stick * (|x| + d/2).
    """
    z = np.asarray(z, float)
    v = z[3] - z[1]
    if abs(v) < v_stick:
        return True
    if side * v >= 0.0:
        return False
    sf = math.copysign(1.0, v) if system.friction_accel > 0.0 else 0.0
    acc = free_affine(system, sf).rate(t, z, r, system.phase)
    a = acc[3] - acc[1]
    if side * a <= 0.0:
        return False
    return v * v / (2.0 * abs(a)) < h_stick * (abs(z[0]) + 0.5 * system.gap)


# ----------------------------------------------------------------------------------------------
# Affine form of the smooth phases: z' = A z + c + F sin(r t + phase)
# ----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Affine:
    A: np.ndarray  # (4, 4)
    c: np.ndarray  # (4,)
    F: np.ndarray  # (4,)

    def rate(self, t: float, z: np.ndarray, r: float, phase: float) -> np.ndarray:
        return self.A @ z + self.c + self.F * math.sin(r * t + phase)

    def rate2(self, t: float, z: np.ndarray, r: float, phase: float) -> np.ndarray:
        """Second time derivative z'' (the system is affine with harmonic forcing)."""
        return self.A @ self.rate(t, z, r, phase) + self.F * (r * math.cos(r * t + phase))


def free_affine(system: System, sf: float = 0.0, contact: tuple | None = None) -> Affine:
    """Free flight of both masses.

    sf       sign of the relative velocity s' while sliding (friction; 0 = no friction force)
    contact  (side, k, c) for the penalty method: linear spring-dashpot force on m,
             F_c = -side * (k delta + c delta'), delta = side * s - d/2 (penetration)
    """
    mu, b, w2 = system.mu, system.beta, system.rp ** 2
    af = system.friction_accel if sf else 0.0
    A = np.zeros((4, 4))
    c = np.zeros(4)
    A[0, 1] = 1.0
    A[2, 3] = 1.0
    A[1] = (-(1.0 + mu * w2), -2.0 * b, mu * w2, 0.0)
    A[3] = (w2, 0.0, -w2, 0.0)
    c[1] = mu * af * sf
    c[3] = -af * sf
    if contact is not None:
        side, k, cd = contact
        # F_c = -k s - cd s' + side k d/2 acts on m (+F_c/mu on y''), -F_c on M (x'')
        fc_z = np.array([k, cd, -k, -cd])
        fc_0 = side * k * 0.5 * system.gap
        A[1] -= fc_z
        c[1] -= fc_0
        A[3] += fc_z / mu
        c[3] += fc_0 / mu
    F = np.array([0.0, system.force_ratio, 0.0, 0.0])
    return Affine(A, c, F)


def stuck_affine(system: System) -> Affine:
    """Both masses moving together (s frozen): (1 + mu) x'' + 2 beta x' + x = f sin."""
    mu, b = system.mu, system.beta
    A = np.zeros((4, 4))
    A[0, 1] = 1.0
    A[2, 3] = 1.0
    row = np.array([-1.0, -2.0 * b, 0.0, 0.0]) / (1.0 + mu)
    A[1] = row
    A[3] = row
    fr = system.force_ratio / (1.0 + mu)
    return Affine(A, np.zeros(4), np.array([0.0, fr, 0.0, fr]))


@dataclass(frozen=True)
class Functional:
    """g(t, z) = w . z + w0 + wf sin(r t + phase): events and contact forces."""

    w: np.ndarray
    w0: float = 0.0
    wf: float = 0.0

    def __call__(self, t: float, z, r: float, phase: float) -> float:
        w = self.w
        return (w[0] * z[0] + w[1] * z[1] + w[2] * z[2] + w[3] * z[3]
                + self.w0 + self.wf * math.sin(r * t + phase))

    def rate(self, t: float, z, aff: Affine, r: float, phase: float) -> float:
        return float(self.w @ aff.rate(t, np.asarray(z, float), r, phase)) + self.wf * r * math.cos(r * t + phase)

    def scaled(self, k: float, shift: float = 0.0) -> "Functional":
        return Functional(k * self.w, k * self.w0 + shift, k * self.wf)


S_POS = np.array([-1.0, 0.0, 1.0, 0.0])   # s  = y - x
S_VEL = np.array([0.0, -1.0, 0.0, 1.0])   # s' = y' - x'


def wall_gap(system: System, side: int) -> Functional:
    """side * s - d/2: crosses zero upward when the mass reaches wall `side`."""
    return Functional(side * S_POS, -0.5 * system.gap, 0.0)


def required_force(system: System, s0: float, contact: tuple | None = None) -> Functional:
    """R: force per unit damper mass the container must supply to keep s frozen at s0.

    R = a_c - g_y, a_c the common acceleration of the stuck pair and g_y the damper
    mass's acceleration from everything but the container contact / friction
    (pendulum restoring force; penalty spring at s0 with s' = 0).
    """
    mu, b = system.mu, system.beta
    w = np.array([-1.0, -2.0 * b, 0.0, 0.0]) / (1.0 + mu)
    gy = -(system.rp ** 2) * s0
    if contact is not None:
        side, k, _ = contact
        delta = side * s0 - 0.5 * system.gap
        if delta > 0.0:
            gy += -side * k * delta / mu
    return Functional(w, -gy, system.force_ratio / (1.0 + mu))


def stuck_exit_functionals(system: System, side: int, s0: float, contact=None) -> list[tuple[Functional, int]]:
    """Functions that cross zero upward when sticking ends, with the side they release to.

    At a rigid wall `side`: the wall can only push the mass inward and friction adds
    at most a_f, so contact holds while side * R <= a_f.  In the interior (side 0,
    friction only) the mass stays stuck while |R| <= a_f.
    Returns [(g, release_sign)] where release_sign = sign(R) at the exit
    (the mass then slides with s' of sign -release_sign).
    """
    af = system.friction_accel
    R = required_force(system, s0, contact)
    if side != 0:
        return [(R.scaled(side, -af), side)]
    return [(R.scaled(1.0, -af), 1), (R.scaled(-1.0, -af), -1)]


def time_resolution(t: float) -> float:
    """Width of the time window an event located at t is resolved to (root finders work
    to a few ulps of t); a constraint function crossing zero within it counts as zero."""
    return 1e-12 * max(1.0, abs(t))


def near_zero(g: Functional, t: float, z, aff: Affine, r: float, phase: float) -> tuple[bool, float, float]:
    """(is g zero to within round-off and event-time resolution, g, g') at (t, z)."""
    z = np.asarray(z, float)
    val = g(t, z, r, phase)
    rate = g.rate(t, z, aff, r, phase)
    size = float(np.abs(g.w) @ np.abs(z)) + abs(g.w0) + abs(g.wf)
    tol = 1e-13 * size + abs(rate) * time_resolution(t)
    return abs(val) <= tol, val, rate


def leaves_now(g: Functional, t: float, z, aff: Affine, r: float, phase: float, scale: float = 0.0) -> bool:
    """Is g > 0 now, or zero and increasing (the constraint is released at once)?

    "Zero" allows for round-off and for the time resolution of the event that
    brought the run here (see :func:`near_zero`).
    """
    zero, val, rate = near_zero(g, t, z, aff, r, phase)
    if not zero:
        return val > 0.0
    if abs(rate) > 1e-13 * max(scale, 1e-300):
        return rate > 0.0
    # second derivative (g is affine in z and harmonic in t)
    zz = aff.rate2(t, np.asarray(z, float), r, phase)
    acc = float(g.w @ zz) - g.wf * r * r * math.sin(r * t + phase)
    return acc > 0.0


# ----------------------------------------------------------------------------------------------
# Bookkeeping
# ----------------------------------------------------------------------------------------------

#: impacts at one wall in a row, each within ZENO_GAP of the previous one, beyond which a
#: chatter sequence is declared unresolved (with the default thresholds a real sequence ends
#: in sticking after a few dozen impacts)
ZENO_IMPACTS = 1000
ZENO_GAP = 1e-3


class ImpactLog:
    def __init__(self):
        self.t: list[float] = []
        self.side: list[int] = []
        self.pre: list[tuple] = []
        self.post: list[tuple] = []
        self.run_length = 0  # current run of close impacts at one wall

    def zeno(self) -> bool:
        """Has the last impact made an unresolved accumulation (see ZENO_IMPACTS)?"""
        return self.run_length > ZENO_IMPACTS

    def add(self, t, side, pre, post=(math.nan, math.nan)) -> int:
        if self.t and self.side[-1] == side and t - self.t[-1] < ZENO_GAP:
            self.run_length += 1
        else:
            self.run_length = 1
        self.t.append(float(t))
        self.side.append(int(side))
        self.pre.append((float(pre[0]), float(pre[1])))
        self.post.append((float(post[0]), float(post[1])))
        return len(self.t) - 1

    def set_post(self, i: int, post) -> None:
        self.post[i] = (float(post[0]), float(post[1]))

    def __len__(self):
        return len(self.t)

    def arrays(self):
        t = np.asarray(self.t, float)
        side = np.asarray(self.side, int)
        pre = np.asarray(self.pre, float).reshape(-1, 2)
        post = np.asarray(self.post, float).reshape(-1, 2)
        return t, side, pre, post


class TrapzWindow:
    """Trapezoid rule for the integral of x^2 over [t_window, t_end] from step points.

    A step straddling t_window is cut there with x linearly interpolated.
    """

    def __init__(self, t_window: float):
        self.tw = t_window
        self.total = 0.0

    def add(self, t0: float, x0: float, t1: float, x1: float) -> None:
        tw = self.tw
        if t1 <= tw or t1 <= t0:
            return
        if t0 < tw:
            x0 = x0 + (x1 - x0) * (tw - t0) / (t1 - t0)
            t0 = tw
        self.total += 0.5 * (t1 - t0) * (x0 * x0 + x1 * x1)


def make_result(log: ImpactLog, *, t_end_req: float, t_reached: float, t_window: float, z,
                x2_integral: float, nfev: int, n_steps: int, max_pen: float, status: str,
                method: str) -> BaselineResult:
    t, side, pre, post = log.arrays()
    ok = status == "ok"
    span = t_reached - t_window
    amp = math.sqrt(2.0 * max(x2_integral, 0.0) / span) if ok and span > 0 else math.nan
    return BaselineResult(
        impact_times=t, impact_side=side, pre=pre, post=post,
        t_end=float(t_reached), final_state=np.array(z, dtype=float),
        amplitude=amp, n_impacts_window=int(np.count_nonzero(t >= t_window)),
        nfev=int(nfev), n_steps=int(n_steps), max_penetration=float(max_pen),
        status=status, method=method,
    )


def start_mode(system: System, side: int, friction_accel: float) -> str:
    """How a run starts: 'locked' (no gap), 'stick' (at a wall, or on a floor with friction) or 'free'."""
    if system.gap == 0.0:
        return "locked"
    if side != 0 or friction_accel > 0.0:
        return "stick"
    return "free"


def stick_from(system: System, seg, stuck: Affine, exits, t: float, z, s0: float, r: float, phase: float,
               scale: float):
    """The damper mass merged with the structure at offset s0 (momentum kept), then the stuck phase."""
    vc = merged_velocity(system.mu, z[1], z[3])
    z = np.array([z[0], vc, z[0] + s0, vc])
    return stuck_phase(seg, stuck, exits, t, z, r, phase, scale)


def after_phase(msg, fired, t: float, t0: float, idle: int) -> tuple[bool, str | None, int]:
    """After a flight phase from t0 to t: (stop, failure, idle).  Stop on a failure (its status) or when no
    event ended the phase (the run's end); a phase that did not advance time counts towards the idle limit."""
    if msg:
        return True, f"failed: {msg}", idle
    if fired is None:
        return True, None, idle
    return False, None, idle + 1 if t - t0 <= 1e-12 * max(1.0, t) else 0


def stuck_phase(seg, stuck: Affine, exits, t: float, z, r: float, phase: float, scale: float):
    """Hold the masses together (affine flow `stuck`) until one of the exit functionals fires.

    seg: the integrator's segment runner (``seg.run(aff, events, t, z) -> (t, z, fired, msg)``);
    exits: [(functional, side released)] (stuck_exit_functionals).  A functional already leaving
    at t releases the mass at once.  Returns (t, z, released, msg, advanced): released is the
    exit's side (None when the run ended or failed, msg then says why); advanced says whether the
    stuck flow moved time on (None: released at once, without running it).  The integrators count
    phases that do not advance, to stop a stick / release cycle.
    """
    for g, rel in exits:
        if leaves_now(g, t, z, stuck, r, phase, scale):
            return t, z, rel, None, None
    t0 = t
    t, z, fired, msg = seg.run(stuck, [(g, +1) for g, _ in exits], t, z)
    if msg or fired is None:
        return t, z, None, msg, True
    return t, z, exits[fired][1], None, t - t0 > 1e-12 * max(1.0, t)
