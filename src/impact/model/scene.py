"""Scenes: a shear building, damper units on its floors, one load (what is simulated; the engine runs it).

    building = Building.uniform(3, period_s=1.0, zeta=0.02)
    damper = Damper("cid", mass=0.02 * building.total_mass, gap=0.05, e=0.5, units=4)
    load = GroundMotion.from_record(load_record("elcentro"), pga_g=0.35)
    result = simulate_scene(Scene(building, (damper,), load))   # impact.engine.scenes
    result.peak_roof_displacement, result.impacts, result.diagnostics

Coordinates are relative to the ground.  A ground acceleration a_g(t) loads
every mass m with -m a_g(t) (damper masses included); a force record loads the
floors it names.  Both are piecewise linear between samples, so the flow
between samples is exact.  After the last sample the load is zero and the
motion decays freely until the scene's duration ends.
"""

from __future__ import annotations

import functools
import math
from dataclasses import KW_ONLY, dataclass

import numpy as np

from impact.model.building import Building
from impact.model.kinds import DamperKind, damper_kinds, kind_of, sliding_kinds
from impact.model.params import (
    G_GRAV,
    MAX_TUNING,
    MIN_TUNING,
    STARTS,
    ParameterError,
    _check,
    check_choice,
    check_fields,
    check_integer,
)

#: a storey's post-yield stiffness b k - P/h must be zero or at least this fraction of k away from it: near zero its
#: mode's particular solution splits into an exponential and a polynomial of size 1/lam^2 that cancel, which the
#: state's own advance (engine.segment.flow_change) keeps out of the state but not out of the rows.  Measured
#: (tests/test_yielding.py, tools/probe_scenes.py): at 8e-4 k the flow matches an independent solution to 1e-12,
#: at 7.4e-6 k a probe scene's energy balance lost 1.6e-7 with the state read off the rows
MIN_TANGENT = 1e-4

#: a storey's stability coefficient theta = P / (k h), the weight it carries over its elastic stiffness times its
#: height, must stay at most this: past it the building is within a twentieth of buckling under its own weight, a
#: mode of the soft storey slows to nothing, and its rows' round-off, read through an ill-conditioned eigenbasis,
#: outgrows the energy balance's 1e-9.  Measured (docs/model.md, "The soft storey, measured"): the balance broke at
#: theta = 0.995 beside a TMD (3.9e-9, probe scene 2572387895-2905) and at 0.998 (4.4e-9); at 0.95 the worst of 161
#: probe scenes with dampers balanced to 1.2e-11, so the bound keeps a margin of ten in the stiffness kept.
#: ASCE 7-16 12.8.7 allows a design at most 0.25
MAX_STABILITY = 0.95

#: a scene's event budget by default, over its degrees of freedom (storeys and units), since an event costs more
#: the more there are: measured with e = 1 units in nanometre gaps, 16 to 20 µs an event on 3 storeys with one unit
#: and 48 to 64 µs on 9 storeys with 12, so such a run ends in 5 to 10 s, the costliest the probe found in 27 s
#: (docs/model.md, "Guard"); the study's runs make hundreds
EVENT_BUDGET_PER_DOF = 2_000_000

DAMPER_KINDS = damper_kinds()  # the registry's kinds (model.kinds), as the study lists them

#: a damper unit's contact with its walls or floor: moving on its own ("free"; a unit that has just struck the
#: wall on `side` and is leaving it says which), resting against the wall on `side` and moving with its floor
#: ("held"), one body with its floor ("locked", a gap of zero) or dragged along by its floor by friction ("floor")
CONTACT_MODES = ("free", "held", "locked", "floor")
_SIGNS = (-1, 0, 1)


@dataclass(frozen=True)
class Contact:
    """One unit's contact state: its mode (CONTACT_MODES), the wall it is on or has just left (side -1 left,
    +1 right, 0 none) and the direction it slides in against friction (slide -1, 0 or +1)."""

    mode: str = "free"
    side: int = 0
    slide: int = 0

    def __post_init__(self):
        check_choice("mode", self.mode, CONTACT_MODES)
        for name in ("side", "slide"):
            if getattr(self, name) not in _SIGNS:
                raise ParameterError(f"{name} = {getattr(self, name)!r} is out of range: allowed -1, 0 or 1")
        if self.mode == "held" and self.side == 0:
            raise ParameterError("side = 0 with mode 'held': a held unit rests against the wall on side -1 or 1")


@dataclass(frozen=True)
class State:
    """Where a run starts or ended: every degree of freedom's displacement and velocity relative to the ground,
    the floors first (storey 1 first), then the units in Scene.unit_list() order, in the scene's units; and each
    unit's Contact.  A run's final State (SceneResult.final) is the next run's Scene(initial=...): a
    continuation."""

    q: tuple
    v: tuple
    contacts: tuple = ()

    def __post_init__(self):
        for name in ("q", "v"):
            values = tuple(float(x) for x in getattr(self, name))
            if not all(math.isfinite(x) for x in values):
                raise ParameterError(f"initial.{name}: every value must be finite")
            object.__setattr__(self, name, values)
        if len(self.q) != len(self.v):
            raise ParameterError(f"initial.q has {len(self.q)} values and initial.v {len(self.v)}: give one each "
                                 "per degree of freedom")
        contacts = tuple(self.contacts)
        for k, c in enumerate(contacts):
            if not isinstance(c, Contact):
                raise ParameterError(f"initial.contacts[{k}] must be a Contact, got {type(c).__name__}")
        object.__setattr__(self, "contacts", contacts)

    @classmethod
    def paper(cls, z, contact: Contact = Contact()) -> "State":
        """The paper's one storey and one unit from its (x, x', y, y'): the structure's and the damper mass's
        displacement and velocity."""
        x, xd, y, yd = (float(c) for c in z)
        return cls((x, y), (xd, yd), (contact,))


@dataclass(frozen=True)
class Damper:
    """One damper, possibly split into `units` identical units on the same floor.

    kind     a kind of model.kinds.KINDS: CID (free mass between walls), PID (pendulum), TMD (spring, dashpot)
    mass     total mass of the damper (all units together)
    gap      total clearance d of each unit (CID, PID)
    e        coefficient of restitution (CID, PID; a TMD's end stops)
    tuning   natural frequency of the pendulum (PID, r') or of the TMD (f) over the building's fundamental one
    damping  damping ratio of the pendulum (PID, optional) or of the TMD
    floor    floor it is attached to, 1 (lowest) to N; None: the roof
    nu       Coulomb friction coefficient under a CID's mass
    units    n identical units of mass mass/n (Bapat & Sankar's multi-unit damper)
    stroke_limit  a kind without walls (TMD): the stroke from its rest place at which its mass meets end stops
    (a built TMD's travel is bounded), struck as an impact damper's walls are, with restitution e; None: no stops
    """

    kind: str
    mass: float
    _: KW_ONLY  # where, and how the damper is built, are named at every call
    gap: float = 0.0
    e: float = 0.0
    tuning: float = 1.0
    damping: float = 0.0
    floor: int | None = None
    nu: float = 0.0
    units: int = 1
    stroke_limit: float | None = None

    def __post_init__(self):
        check_choice("kind", self.kind, damper_kinds())  # the registry as it is now: a kind added later counts
        kind = kind_of(self.kind)
        tuning_floor = f"[{MIN_TUNING:g}" if kind.spring else "[0"
        check_fields(self, mass="(0, 1e15]", gap="[0, 1e12]", e="[0, 1]", tuning=f"{tuning_floor}, {MAX_TUNING:g}]",
                     damping="[0, 1)", nu="[0, 100]")
        check_integer("units", self.units, 1, 60)
        if self.nu > 0.0 and not kind.slides:
            raise ParameterError(f"nu is only defined for kind {sliding_kinds()} (only a free mass slides on a floor)")
        if not kind.walls and self.gap:
            raise ParameterError(f"gap is not defined for kind {self.kind!r} (a {kind.title} has no walls): leave "
                                 "it at 0")
        _check_floor("floor", self.floor)
        if self.stroke_limit is not None:
            if kind.walls:
                raise ParameterError(f"stroke_limit is not defined for kind {self.kind!r}: its walls limit its "
                                     "stroke to half its gap")
            check_fields(self, stroke_limit="(0, 1e6]")

    @property
    def kind_spec(self) -> DamperKind:
        """What this damper's units are made of (model.kinds)."""
        return kind_of(self.kind)

    @property
    def has_walls(self) -> bool:
        """Whether its units strike: its kind's walls, or a wall-less kind's end stops."""
        return self.kind_spec.walls or self.stroke_limit is not None

    @property
    def clearance(self) -> float:
        """The distance between a unit's walls (or end stops) that its mass travels in: 0 where it has none."""
        if self.kind_spec.walls:
            return self.gap
        return 0.0 if self.stroke_limit is None else 2.0 * self.stroke_limit


@dataclass(frozen=True, eq=False)
class Harmonic:
    """A force F0 sin(Omega t + phi) on one floor (None: the roof).  F0 = 0 is no force: the scene's free vibration
    from its initial State (a free decay)."""

    amplitude: float
    omega: float
    phase: float = 0.0
    floor: int | None = None

    def __post_init__(self):
        _check("amplitude", self.amplitude, 0.0, 1e18)
        _check("omega", self.omega, 0.0, 1e6, lo_open=True)
        _check("phase", self.phase, -2 * math.pi, 2 * math.pi)
        _check_floor("floor", self.floor)


def _check_floor(name: str, floor) -> None:
    """A floor is None (the roof) or a whole number from 1; the building's height is checked by the Scene."""
    if floor is not None:
        check_integer(name, floor, 1)


def _samples(name: str, values, dt: float) -> np.ndarray:
    """A record's samples as a finite 1-d float array of at least two, with a valid step dt."""
    a = np.asarray(values, dtype=float)
    if a.ndim != 1 or len(a) < 2 or not np.all(np.isfinite(a)):
        raise ParameterError(f"{name} must be a finite 1-d array of at least two samples")
    _check("dt", dt, 0.0, 1e3, lo_open=True)
    return a


@dataclass(frozen=True, eq=False)
class GroundMotion:
    """A ground acceleration sampled every dt (m/s^2 in physical units), piecewise linear between samples."""

    accel: np.ndarray
    dt: float
    name: str = "record"

    def __post_init__(self):
        object.__setattr__(self, "accel", _samples("accel", self.accel, self.dt))

    @classmethod
    def from_record(cls, record, pga_g: float | None = None, gravity: float = G_GRAV) -> "GroundMotion":
        """From a :class:`impact.model.records.Record` (values in g), optionally scaled to a PGA in g."""
        accel_g = record.accel_g if pga_g is None else record.scaled_to_pga_g(pga_g)
        return cls(accel_g * gravity, record.dt, record.name)

    @property
    def duration(self) -> float:
        return self.dt * (len(self.accel) - 1)

    @property
    def pga(self) -> float:
        return float(np.max(np.abs(self.accel)))


@dataclass(frozen=True, eq=False)
class ForceRecord:
    """Forces sampled every dt: F_i(t) = distribution[i] * values(t), piecewise linear.

    distribution has one entry per floor, then optionally one per damper unit.
    """

    values: np.ndarray
    dt: float
    distribution: np.ndarray
    name: str = "force"

    def __post_init__(self):
        object.__setattr__(self, "values", _samples("values", self.values, self.dt))
        dist = np.atleast_1d(np.asarray(self.distribution, dtype=float))
        if dist.ndim != 1 or not np.all(np.isfinite(dist)):
            raise ParameterError("distribution must be a finite 1-d array: one weight per floor (and unit)")
        object.__setattr__(self, "distribution", dist)

    @property
    def duration(self) -> float:
        return self.dt * (len(self.values) - 1)


@dataclass(frozen=True, eq=False)
class Scene:
    """A building, its dampers, one load, and how long to run.

    duration
        simulated time; for a record, None means the record's length
    window
        the RMS window starts here (None: 0 for records, half the duration for a harmonic load)
    start
        where every wall damper's mass starts: centre, or resting on the left or right wall
    gravity
        acceleration of gravity in the scene's units, those its building was given in: m/s² for a building in
        SI, 1 in the paper's model units (friction only)
    unit_starts
        each unit's initial displacement from the middle of its walls, in unit_list() order (overrides start; a unit
        at +-d/2 rests on that wall; a TMD's entry must be 0)
    max_events_per_period
        a bound on a run's cost, not a limit of the physics: an elastic unit held on one wall of a 5e-7 m gap
        bounces every 3e-6 s, 1e6 events a period, all resolved.  A run that reaches it, or makes 1000 events
        within 1e-9 of a period (a loop without progress, which the engine guards against), ends flagged
        (event_cap_reached)
    max_events
        the run's event budget, its events in all (None: EVENT_BUDGET_PER_DOF over the storeys and units,
        event_budget): a run that would resolve more (an e = 1 unit in a gap of nanometres, tens of millions of
        impacts) ends flagged (event_cap_reached, stopped_by 'event budget') after this many, in seconds, not
        minutes.  The study's record runs make hundreds; raise it to see such a run through
    collapse_drift_ratio
        a yielding building's run stops as a collapse once a storey's drift passes this fraction of its height
        (None: never; needs the building's storey heights)
    initial
        the State the run starts from, every degree of freedom's displacement and velocity and every unit's
        contact (None: at rest, the units placed by start or unit_starts, which it overrides); a run's final
        State continues it (SceneResult.final)
    """

    building: Building
    dampers: tuple = ()
    load: object = None
    duration: float | None = None
    window: float | None = None
    start: str = "centre"
    gravity: float = G_GRAV
    max_events_per_period: int = 2_000_000
    unit_starts: tuple | None = None
    collapse_drift_ratio: float | None = None
    max_events: int | None = None
    initial: State | None = None

    def __post_init__(self):
        object.__setattr__(self, "dampers", tuple(self.dampers))
        check_choice("start", self.start, STARTS)
        if not isinstance(self.load, (Harmonic, GroundMotion, ForceRecord)):
            raise ParameterError(f"load = {self.load!r} is not a load: give a Harmonic, GroundMotion or ForceRecord")
        if not isinstance(self.building, Building):
            raise ParameterError(f"building must be a Building, got {type(self.building).__name__}")
        n = self.building.storeys
        for i, d in enumerate(self.dampers):
            if not isinstance(d, Damper):
                raise ParameterError(f"dampers[{i}] must be a Damper, got {type(d).__name__}")
            if d.floor is not None and not 1 <= d.floor <= n:
                raise ParameterError(f"dampers[{i}].floor = {d.floor} is out of range: allowed [1, {n}]")
        if isinstance(self.load, Harmonic) and self.load.floor is not None and not 1 <= self.load.floor <= n:
            raise ParameterError(f"load.floor = {self.load.floor} is out of range: allowed [1, {n}]")
        if self.duration is None and isinstance(self.load, Harmonic):
            raise ParameterError("duration is required for a harmonic load")
        if self.duration is not None:
            _check("duration", self.duration, 0.0, 1e9, lo_open=True)
        if self.window is not None:
            _check("window", self.window, 0.0, self.t_end, hi_open=True)
        _check("gravity", self.gravity, 0.0, 1e6, lo_open=True)
        check_integer("max_events_per_period", self.max_events_per_period, 10)
        if self.max_events is not None:
            check_integer("max_events", self.max_events, 10)
        if len(self.unit_list()) > 60:
            raise ParameterError("at most 60 damper units in one scene")
        if not self.building.is_elastic and len(self.unit_list()) + n > 62:
            raise ParameterError("a yielding building's units and storeys are at most 62 in one scene")
        if not self.building.is_elastic:
            self._check_tangents()
        if self.collapse_drift_ratio is not None:
            _check("collapse_drift_ratio", self.collapse_drift_ratio, 0.0, 10.0, lo_open=True)
            if self.building.storey_height is None:
                raise ParameterError("collapse_drift_ratio needs the building's storey_height")
        if self.unit_starts is not None:
            self._check_unit_starts()
        if self.initial is not None:
            self._check_initial()

    def _check_unit_starts(self) -> None:
        starts = tuple(float(x) for x in self.unit_starts)
        units = self.unit_list()
        if len(starts) != len(units):
            raise ParameterError(f"unit_starts has {len(starts)} values for {len(units)} damper units: give one per unit")
        for k, (x, (_, d)) in enumerate(zip(starts, units)):
            half = 0.5 * d.clearance
            _check(f"unit_starts[{k}]", x, -half, half)
        object.__setattr__(self, "unit_starts", starts)

    def _check_initial(self) -> None:
        state, units = self.initial, self.unit_list()
        if not isinstance(state, State):
            raise ParameterError(f"initial must be a State, got {type(state).__name__}")
        if self.unit_starts is not None:
            raise ParameterError("initial and unit_starts both place the units: give one of them")
        n = self.building.storeys + len(units)
        if len(state.q) != n or len(state.contacts) != len(units):
            raise ParameterError(f"initial has {len(state.q)} degrees of freedom and {len(state.contacts)} contacts; "
                                 f"this scene has {n} ({self.building.storeys} floors, {len(units)} units) and "
                                 f"{len(units)} contacts")
        for k, (c, (_, d)) in enumerate(zip(state.contacts, units)):
            stroke = state.q[self.building.storeys + k] - state.q[self.floor_index(d.floor)]
            half = 0.5 * d.clearance if d.has_walls else math.inf
            if abs(stroke) > half * (1.0 + 1e-12):
                raise ParameterError(f"initial.q: unit {k}'s stroke {stroke:g} is beyond its walls: allowed "
                                     f"[{-half:g}, {half:g}]")
            if c.mode != "free" and not d.has_walls:
                raise ParameterError(f"initial.contacts[{k}].mode = {c.mode!r}: a {d.kind} unit has no walls, "
                                     "it is 'free'")

    @property
    def event_budget(self) -> int:
        """The events a run may resolve in all: max_events, or EVENT_BUDGET_PER_DOF over the degrees of freedom."""
        if self.max_events is not None:
            return self.max_events
        return EVENT_BUDGET_PER_DOF // (self.building.storeys + len(self.unit_list()))

    @property
    def t_end(self) -> float:
        return float(self.duration) if self.duration is not None else self.load.duration

    @property
    def t_window(self) -> float:
        if self.window is not None:
            return float(self.window)
        return 0.5 * self.t_end if isinstance(self.load, Harmonic) else 0.0

    def unit_list(self) -> list[tuple[int, Damper]]:
        """(damper index, damper) for every unit."""
        return [(i, d) for i, d in enumerate(self.dampers) for _ in range(int(d.units))]

    def floor_index(self, floor: int | None) -> int:
        return self.building.storeys - 1 if floor is None else int(floor) - 1

    def carried_masses(self) -> np.ndarray:
        """The mass on every floor, floor 1 first: the floor's own and its damper units'."""
        carried = self.building.masses.copy()
        for _, d in self.unit_list():
            carried[self.floor_index(d.floor)] += d.mass / d.units
        return carried

    def geometric_stiffness(self) -> np.ndarray:
        """P-delta's stiffness P_i / h_i of every storey (zeros without P-delta), Building.geometric_stiffness with
        the dampers' weight and the scene's gravity."""
        return self.building.geometric_stiffness(self.carried_masses(), self.gravity)

    def stability_coefficients(self) -> np.ndarray:
        """Every storey's stability coefficient theta = P / (k h) (zeros without P-delta), storey 1 first, with the
        dampers' weight and the scene's gravity."""
        return self.building.stability_coefficients(self.carried_masses(), self.gravity)

    def post_yield_stiffness(self) -> np.ndarray | None:
        """Every storey's stiffness on its yielding branch, b k - P/h (N/m), storey 1 first; None for a building
        whose storeys do not yield."""
        b = self.building
        if b.yield_drift is None:
            return None
        return b.hardening * b.storey_stiffness - self.geometric_stiffness()

    def _check_tangents(self) -> None:
        """Refuse a storey whose stability coefficient passes MAX_STABILITY (its elastic stiffness k - P/h near zero)
        or whose post-yield stiffness b k - P/h is near zero (a zero post-yield stiffness is allowed only without
        P-delta: b = 0, a perfectly plastic storey), and a building that can fall over (a negative post-yield
        stiffness) without a collapse limit to stop its run."""
        b = self.building
        geometric = self.geometric_stiffness()
        for i, theta in enumerate(self.stability_coefficients(), start=1):
            if theta > MAX_STABILITY:
                raise ParameterError(f"storey {i}: P-delta's stability coefficient theta = P/(k h) = {theta:.6g} is "
                                     f"out of range: allowed [0, {MAX_STABILITY:g}] (at 1 the building cannot stand; "
                                     "near it the energy balance is lost to round-off): raise the storey's stiffness, "
                                     "or lower its storey_height or the weight it carries")
        tangents = self.post_yield_stiffness()
        if tangents is None:
            return
        for i, (ki, gi, tangent) in enumerate(zip(b.storey_stiffness, geometric, tangents), start=1):
            if abs(tangent) < MIN_TANGENT * ki and not (tangent == 0.0 and gi == 0.0):
                raise ParameterError(
                    f"hardening = {b.hardening!r} leaves storey {i} a post-yield stiffness b k - P/h of "
                    f"{tangent / ki:.2e} k: allowed 0 without P-delta (b = 0), else at least {MIN_TANGENT:g} k in "
                    "size (the exact flow loses digits near a zero stiffness)")
            if tangent < 0.0 and self.collapse_drift_ratio is None:
                raise ParameterError(f"storey {i}'s post-yield stiffness b k - P/h is negative: once it yields its "
                                     "drift can grow without bound, so give collapse_drift_ratio to stop the run")


@functools.lru_cache(maxsize=64)
def _paper_building(beta: float) -> Building:
    """Building.paper(beta), built once per damping: a sweep's thousands of runs share their structure (its
    arrays read-only, so that sharing is safe), which halves what building a run's scene costs."""
    building = Building.paper(beta)
    for values in (building.masses, building.storey_stiffness, building.damping):
        values.flags.writeable = False
    return building


@functools.lru_cache(maxsize=256)
def _paper_damper(kind: str, mu: float, gap: float, e: float, tuning: float, nu: float, units: int) -> Damper:
    """The paper's damper of these numbers, checked once: a sweep's runs share it (Damper is frozen)."""
    return Damper(kind, mass=mu, gap=gap, e=e, tuning=tuning, nu=nu, units=units)


def paper_scene(kind: str, mu: float, beta: float, e: float, gap: float, r: float, *, rp: float = 0.0,
                force_ratio: float = 0.096, periods: float = 500.0, average_from: float = 250.0,
                start: str = "centre", units: int = 1, nu: float = 0.0, gravity: float = G_GRAV,
                phase: float = 0.0, max_events_per_period: int = 20000, initial: State | None = None) -> Scene:
    """The paper's one-storey structure in model units (M = 1, omega = 1) as a scene."""
    building = _paper_building(float(beta))
    damper = _paper_damper(kind, float(mu), float(gap), float(e), float(rp) if kind_of(kind).spring else 0.0,
                           float(nu), int(units))
    period = 2.0 * math.pi
    # the protocol bounds a run by its periods and its cap per period, as the paper loop's own runs: no budget
    budget = max_events_per_period * (math.ceil(periods) + 1)
    return Scene(building, (damper,), Harmonic(force_ratio, r, phase), duration=periods * period,
                 window=average_from * period, start=start, gravity=gravity,
                 max_events_per_period=max_events_per_period, max_events=budget, initial=initial)


def _gravity_of_friction(nu: float, a_f: float) -> float:
    """The scene's gravity for the paper system's friction: a_f / nu, or the float next to it when that is the one
    whose product with nu is a_f again, so that the scene's friction, nu times its gravity, is the system's to the
    bit (a run of the system and of its scene are then the same run)."""
    g = a_f / nu
    for candidate in (g, math.nextafter(g, math.inf), math.nextafter(g, -math.inf)):
        if nu * candidate == a_f:
            return candidate
    return g


def paper_scene_from_system(system, r: float, protocol, units: int = 1, initial: State | None = None) -> Scene:
    """The scene of one run of the paper kernel (impact.model.params System and Protocol), optionally multi-unit."""
    gravity = _gravity_of_friction(system.nu, system.friction_accel) if system.nu > 0 else G_GRAV
    return paper_scene(system.kind, system.mu, system.beta, system.e, system.gap, r, rp=system.rp,
                       force_ratio=system.force_ratio, periods=protocol.periods, average_from=protocol.average_from,
                       start=protocol.start, units=units, nu=system.nu, gravity=gravity, phase=system.phase,
                       max_events_per_period=protocol.max_events_per_period, initial=initial)
