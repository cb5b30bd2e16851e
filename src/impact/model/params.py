"""Model parameters and the response protocol, in model units.

Model units (model.md, "Symbols and scaling"): the structure's mass M = 1, its
natural frequency omega = 1 (time unit 1/omega, natural period 2*pi) and lengths
in the paper's "units".  The force amplitude enters as the static deflection
``force_ratio`` = F0/K, so the bare structure's resonant amplitude is
A_max = (F0/K) / (2 beta).

Every constructor validates its input and raises :class:`ParameterError`
naming the field and its allowed range, so the command line, the pipeline and
the library refuse bad input with the same words.
"""

from __future__ import annotations

import functools
import math
from dataclasses import KW_ONLY, asdict, dataclass, field

import numpy as np

from impact.model.kinds import KINDS, impact_kinds, sliding_kinds

IMPACT_KINDS = impact_kinds()  # the dampers with walls (model.kinds): the paper's two
#: the kinds the paper's system (System, the paper's loop) runs
PAPER_KINDS = tuple(name for name, k in KINDS.items() if k.paper)
STARTS = ("centre", "left", "right")
G_GRAV = 9.80665  # m/s^2, standard gravity


class ParameterError(ValueError):
    """A parameter outside its allowed range; the message names the field."""


#: the highest tuning of a scene's PID or TMD (its frequency over the building's fundamental): beyond it the
#: damper's spring is over 1e4 times the building's stiffness per mass, and the modal tables' round-off, which
#: grows about as tuning^1.5 to tuning^2, passes the 1e-9 to which every run balances.  Measured on 40 probe
#: scenes with their PIDs and TMDs made TMDs of one tuning (no impacts): the largest residual was 1.1e-11 at 30,
#: 1.5e-10 at 100, 5.7e-10 at 300 and 4.2e-9 at 1e3 (2 of the 40 beyond 1e-9; tools/tuning_bounds.py); probe scene 3761029462-2512, a
#: PID of tuning 400: 1.7e-9, and 1.9e-10 with that PID at 100.  (It was 1e3, from one scene's 2e-10 there.)
MAX_TUNING = 100.0
#: the lowest tuning of a scene's PID or TMD.  A PID or TMD tuned ten times below the building's fundamental damps
#: nothing of it, and below that the damper's mode is so soft that a load record's particular solution (the static
#: response, which grows as 1 / tuning^2) and a segment's modal part cancel, which costs the energy balance digits.
#: Measured on 40 probe scenes with every PID and TMD set to one tuning (tools/tuning_bounds.py), since the
#: dissipation is integrated in the ramp form (docs/model.md, "Energy balance"): the largest residual was 4.5e-12 at
#: 0.1, 7.0e-12 at 0.03 and 4.1e-11 at 0.01, none beyond the 1e-9 to which every run balances (before it: 1.2e-11,
#: 6.8e-10 and 3.8e-8, 4 of 40 beyond); a 10-storey building with a TMD alone: 2.6e-10 at 0.01, 1.4e-8 at 0.001.
MIN_TUNING = 0.1


def _check(name: str, value: float, lo: float, hi: float, *, lo_open=False, hi_open=False) -> float:
    value = float(value)
    below = value <= lo if lo_open else value < lo
    above = value >= hi if hi_open else value > hi
    if not math.isfinite(value) or below or above:
        lb = "(" if lo_open else "["
        rb = ")" if hi_open else "]"
        raise ParameterError(f"{name} = {value!r} is out of range: allowed {lb}{lo}, {hi}{rb}")
    return value


def check_integer(name: str, value, lo: int, hi: float = math.inf) -> int:
    """Refuse a value that is not a whole number in [lo, hi] (a bool, text, NaN, 2.5), naming the field."""
    whole = (not isinstance(value, bool) and isinstance(value, (int, float, np.integer, np.floating))
             and math.isfinite(value) and int(value) == value)
    if not whole or not lo <= value <= hi:
        allowed = f"[{lo}, {hi:g}]" if math.isfinite(hi) else f">= {lo}"
        raise ParameterError(f"{name} = {value!r} is out of range: allowed integers {allowed}")
    return int(value)


def check_choice(name: str, value, allowed) -> None:
    """Refuse a value that is not one of ``allowed``, naming the field and the choices."""
    if value not in allowed:
        raise ParameterError(f"{name} = {value!r} is not allowed: choose one of {', '.join(allowed)}")


@functools.lru_cache(maxsize=256)
def _interval(text: str) -> tuple[float, float, bool, bool]:
    """(lo, hi, lo_open, hi_open) of an interval written "[lo, hi)": read once, since a sweep checks the same
    intervals for each of its thousands of runs."""
    lo, hi = (float(bound) for bound in text[1:-1].split(","))
    return lo, hi, text[0] == "(", text[-1] == ")"


def check_fields(obj, **allowed: str) -> None:
    """Check each named field of ``obj`` against its interval, written as the error message writes it."""
    for name, interval in allowed.items():
        lo, hi, lo_open, hi_open = _interval(interval)
        _check(name, getattr(obj, name), lo, hi, lo_open=lo_open, hi_open=hi_open)


def frequency_grid(r_min: float, r_max: float, r_step: float) -> np.ndarray:
    """Inclusive grid r_min, r_min + step, ..., r_max, free of accumulated round-off."""
    n = int(math.floor((r_max - r_min) / r_step + 1e-9)) + 1
    return np.round(r_min + r_step * np.arange(n), 12)


def a_max(beta: float, force_ratio: float) -> float:
    """Resonant amplitude of the bare structure, (F0/K)/(2 beta); inf for beta = 0."""
    return math.inf if beta == 0.0 else force_ratio / (2.0 * beta)


def friction_acceleration(nu: float, frequency_hz: float, unit_m: float) -> float:
    """Coulomb friction acceleration nu*g in model units (time 1/omega, length one unit).

    model.md: a_f = nu * g_grav / (omega^2 * L_unit) with omega = 2*pi*frequency_hz.
    """
    omega = 2.0 * math.pi * frequency_hz
    return nu * G_GRAV / (omega * omega * unit_m)


@dataclass(frozen=True)
class System:
    """One impact-damper system (structure + damper), model units.

    kind          a kind with walls (model.kinds): the CID (Masri's free mass) or the PID (linearised pendulum)
    mu            mass ratio m/M
    beta          structural damping ratio
    e             coefficient of restitution
    gap           total clearance d (model units); the walls sit at y - x = +-d/2
    rp            pendulum tuning ratio r' = omega_p/omega (PID only; 0 for the CID)
    force_ratio   F0/K, the static deflection under the force amplitude
    phase         force phase phi: F = F0 sin(Omega t + phi)
    nu            Coulomb friction coefficient under the free mass (CID only)
    frequency_hz  structure frequency, sets the friction scale only
    unit_m        length of one model unit in metres, sets the friction scale only
    """

    kind: str
    mu: float
    beta: float
    e: float
    gap: float
    _: KW_ONLY  # the optional parameters are named at every call
    rp: float = 0.0
    force_ratio: float = 0.096
    phase: float = 0.0
    nu: float = 0.0
    frequency_hz: float = 1.5
    unit_m: float = 0.01

    def __post_init__(self):
        check_choice("kind", self.kind, PAPER_KINDS)
        check_fields(self, mu="(0, 10]", beta="[0, 1)", e="[0, 1]", gap="[0, 1e12]",
                     force_ratio="[0, 1e12]", phase=f"[{-2 * math.pi}, {2 * math.pi}]", nu="[0, 100]",
                     frequency_hz="(0, 1e6]", unit_m="(0, 1e6]")
        kind = KINDS[self.kind]
        if kind.spring:
            # a scene's range (model.scene.Damper), named as the paper names the tuning: every run of a System is
            # a scene's (impact.engine.run.simulate_system).  The paper loop's limit r' -> 0, the CID, is a test
            # of that loop called directly (tests/test_core.py)
            check_fields(self, rp=f"[{MIN_TUNING:g}, {MAX_TUNING:g}]")
        if not kind.spring and self.rp != 0.0:
            raise ParameterError(f"rp = {self.rp!r} is not allowed for kind {self.kind!r}: the CID has no pendulum")
        if not kind.slides and self.nu != 0.0:
            raise ParameterError(f"nu is only defined for kind {sliding_kinds()} (the pendulum mass does not slide on a "
                                 "floor)")

    @classmethod
    def from_gap_ratio(cls, kind: str, mu: float, beta: float, e: float, gap_ratio: float, **kw) -> "System":
        """Build a system with d = g * A_max (the paper's gap ratio g = d / A_max)."""
        _check("gap_ratio", gap_ratio, 0.0, 1e6)
        _check("beta", beta, 0.0, 1.0, lo_open=True, hi_open=True)
        return cls(kind=kind, mu=mu, beta=beta, e=e, gap=gap_ratio * a_max(beta, kw.get("force_ratio", 0.096)), **kw)

    @property
    def a_max(self) -> float:
        return a_max(self.beta, self.force_ratio)

    @property
    def gap_ratio(self) -> float:
        return self.gap / self.a_max if self.a_max else math.nan  # no force (a free decay): no A_max

    @property
    def friction_accel(self) -> float:
        return friction_acceleration(self.nu, self.frequency_hz, self.unit_m)

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class Protocol:
    """The paper's response protocol (model.md, "Response protocol").

    periods
        natural periods simulated (2*pi each)
    average_from
        the amplitude window starts after this many periods
    start
        damper mass's initial place: 'centre', 'left' or 'right' wall
    max_events_per_period
        guard against impact accumulations: exceeding it ends the run with a flag instead of looping
    """

    periods: float = 500.0
    average_from: float = 250.0
    start: str = "centre"
    max_events_per_period: int = 20000
    extra: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self):
        _check("periods", self.periods, 0.0, 1e7, lo_open=True)
        _check("average_from", self.average_from, 0.0, self.periods, hi_open=True)
        check_choice("start", self.start, STARTS)
        check_integer("max_events_per_period", self.max_events_per_period, 10)

    @property
    def t_end(self) -> float:
        return 2.0 * math.pi * self.periods

    @property
    def t_window(self) -> float:
        return 2.0 * math.pi * self.average_from


IPC_CLASSES = ("<1 IPC", "1 IPC", "2 IPC", ">2 IPC")


def ipc_class(aipc: float) -> int:
    """The paper's impacts-per-cycle class: 0 '<1', 1 '1 IPC', 2 '2 IPC', 3 '>2' (-1 if undefined)."""
    if not math.isfinite(aipc):
        return -1
    if aipc < 0.5:
        return 0
    if aipc < 1.5:
        return 1
    if aipc <= 2.5:
        return 2
    return 3


def ipc_label(aipc: float) -> str:
    """The IPC class's name (IPC_CLASSES), or 'undefined'."""
    cls = ipc_class(aipc)
    return IPC_CLASSES[cls] if cls >= 0 else "undefined"


def _fmt(x: float) -> str:
    return f"{x:g}"


def curve_id(spec: dict) -> str:
    """File-name id of a curve from its parameters, e.g. 'pid_mu0.01_e0.25_rp1'."""
    name = f"{spec['damper']}_mu{_fmt(spec['mu'])}_e{_fmt(spec['e'])}"
    if KINDS[spec["damper"]].spring:
        name += f"_rp{_fmt(spec['rp'])}"
    if spec.get("nu", 0.0):
        name += f"_nu{_fmt(spec['nu'])}"
        if "frequency_hz" in spec:
            name += f"_f{_fmt(spec['frequency_hz'])}"
        if "unit_m" in spec:
            name += f"_L{_fmt(spec['unit_m'])}"
    return name
