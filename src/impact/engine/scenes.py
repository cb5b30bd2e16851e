"""Runs of scenes on the exact engine: the scene's arrays, the scene loop, and the measures it certifies.

    result = simulate_scene(Scene(building, (damper,), load))
    result.peak_roof_displacement, result.impacts, result.diagnostics

The scene itself (:mod:`impact.model.scene`) is plain data; this module assembles the arrays the compiled loop
(:mod:`impact.engine.scene_loop`) takes and reads its outputs back into a :class:`SceneResult`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from impact.engine import layout as L
from impact.engine.bundles import (
    BuildingArrays,
    ConfigCache,
    MonitorArrays,
    RunOutputs,
    SceneArrays,
    SpringArrays,
    StartState,
    UnitArrays,
    YieldArrays,
)
from impact.engine.clear_step import clear_step_tables
from impact.engine.contact import STICK_VELOCITY, free_vibration_stick
from impact.engine.diagnostics import read_diagnostics
from impact.engine.jitcache import compile_lock
from impact.engine.scene_loop import run_scene
from impact.model.building import Building
from impact.model.kinds import KINDS
from impact.model.params import ParameterError
from impact.model.scene import MAX_STABILITY, Contact, Damper, ForceRecord, GroundMotion, Harmonic, Scene, State

CACHE_SLOTS = 16        # configurations whose eigen-data are kept at once


class EndsInState:
    """A run's result that ends in a State: its final_q, final_v and final_contacts."""

    @property
    def final(self) -> State:
        """The State the run ended in: a Scene (or run.simulate_system) started from it continues the run."""
        return State(self.final_q, self.final_v, self.final_contacts)


@dataclass
class SceneResult(EndsInState):
    """Measures of one scene run, in the units the scene's building and load were given in: metres, seconds and
    m/s² for a building in SI (kg, N/m) under a GroundMotion in m/s² or a force in N; the paper's model units
    (M = K = 1, omega = 1) for its harmonic study."""

    scene: Scene
    peak_roof_displacement: float
    peak_roof_displacement_time: float
    rms_roof_displacement: float
    peak_roof_acceleration: float
    peak_interstorey_drift: float
    peak_drifts: np.ndarray
    peak_strokes: np.ndarray
    impacts: int
    diagnostics: dict
    final_q: np.ndarray
    final_v: np.ndarray
    records: dict | None = field(default=None, repr=False)
    #: dense output: "t" the times, "q" and "v" every degree of freedom there, and "q_roundoff" each position's
    #: round-off, the size of its row's terms times events.PEAK_NOISE (what a sample is known to)
    samples: dict | None = field(default=None, repr=False)
    #: the paper's amplitude, sqrt(2) RMS of the roof over the window
    amplitude: float = math.nan
    #: the time the run spent in the window (its end less the window's start)
    window_span: float = math.nan
    #: the engine's loop that ran (impact.engine.run.LOOPS); what it does not measure is NaN
    loop: str = "scene"
    #: a yielding building's storeys (StoreyResponse); None for an elastic one
    storeys: "StoreyResponse | None" = None
    #: every unit's contact at the run's end (impact.model.scene.Contact), in Scene.unit_list() order
    final_contacts: tuple = ()
    #: what each certified peak is certified to: every value of the monitor over the run lies below
    #: peak (1 + 1e-12) + this, the round-off of the rows the motion is written in (events.peak_abs), 0 where no
    #: search needed it; in the monitors' order: the roof's displacement and acceleration, each storey's drift,
    #: each damper's stroke (NaN where not asked for).  None from a loop that does not certify peaks so
    peak_roundoff: np.ndarray | None = field(default=None, repr=False)

    def as_json(self, units: str = "m") -> dict:
        out = {
            f"peak_roof_displacement_{units}": self.peak_roof_displacement,
            f"rms_roof_displacement_{units}": self.rms_roof_displacement,
            f"peak_roof_acceleration_{units}s2": self.peak_roof_acceleration,
            f"peak_interstorey_drift_{units}": self.peak_interstorey_drift,
            f"peak_damper_stroke_{units}": [float(x) for x in self.peak_strokes],
            "impacts": self.impacts,
            "diagnostics": self.diagnostics,
        }
        if self.peak_roundoff is not None:
            out["peak_roundoff"] = self._roundoff_json(units)
        if self.storeys is not None:
            out.update(self.storeys.as_json(units))
        return out

    def _roundoff_json(self, units: str) -> dict:
        """What each certified peak is known to (peak_roundoff), named as the peaks are."""
        r, parts = self.peak_roundoff, _parts(len(self.peak_drifts))
        return {f"roof_displacement_{units}": float(r[0]), f"roof_acceleration_{units}s2": float(r[1]),
                f"drifts_{units}": [float(x) for x in r[parts["drifts"]]],
                f"damper_strokes_{units}": [float(x) for x in r[parts["strokes"]]]}


@dataclass
class StoreyResponse:
    """What a yielding building's storeys did, storey 1 first; lengths in the scene's units, work in its energy's.

    residual_drifts: the drift each storey settles to at rest from the run's end, unloading elastically (every
    storey shear is zero at rest: (1 - b) p without P-delta, (1 - b) k p / (k - P/h) with it); NaN where no such
    rest exists (P-delta outweighs the elastic stiffness, or the rest lies beyond the yield surface), and then
    has_rest is False.
    """

    peak_drifts: np.ndarray
    plastic_offsets: np.ndarray
    residual_drifts: np.ndarray
    ductility: np.ndarray
    yield_events: np.ndarray
    plastic_work: float
    collapsed: bool
    has_rest: bool

    def as_json(self, units: str = "m") -> dict:
        return {f"peak_drifts_{units}": self.peak_drifts.tolist(),
                f"residual_drifts_{units}": [None if math.isnan(x) else float(x) for x in self.residual_drifts],
                f"plastic_offsets_{units}": self.plastic_offsets.tolist(),
                "plastic_work_J": float(self.plastic_work), "yield_events": int(np.sum(self.yield_events)),
                "ductility": self.ductility.tolist(), "collapsed": bool(self.collapsed)}


# ----------------------------------------------------------------------------
# assembly of the kernel's arrays
# ----------------------------------------------------------------------------

def _unit_bits(damper: Damper) -> int:
    """A unit's kind as the engine reads it: what it is made of (layout.UNIT_*), not its name; a TMD's end stops
    are walls as an impact damper's are."""
    return (L.UNIT_WALLS if damper.has_walls else 0) | (L.UNIT_SPRING if damper.kind_spec.spring else 0)


def _unit_arrays(scene: Scene, omega1: float):
    units = scene.unit_list()
    kind = np.array([_unit_bits(d) for _, d in units], dtype=np.int64)
    floor = np.array([scene.floor_index(d.floor) for _, d in units], dtype=np.int64)
    mass = np.array([d.mass / d.units for _, d in units])
    gap = np.array([d.clearance for _, d in units])
    e = np.array([d.e for _, d in units])
    k = np.array([m * (d.tuning * omega1) ** 2 if d.kind_spec.spring else 0.0 for m, (_, d) in zip(mass, units)])
    c = np.array([2.0 * m * d.damping * d.tuning * omega1 if d.kind_spec.dashpot else 0.0
                  for m, (_, d) in zip(mass, units)])
    a_f = np.array([d.nu * scene.gravity for _, d in units])
    return kind, floor, mass, gap, e, k, c, a_f


def _load_arrays(scene: Scene, mass_full: np.ndarray):
    """(load vector over all degrees of freedom, harmonic, record values, mon_rec, record dt)."""
    nf = scene.building.storeys
    load = scene.load
    vec = np.zeros(len(mass_full))
    if isinstance(load, Harmonic):
        vec[scene.floor_index(load.floor)] = load.amplitude
        return vec, np.array([load.amplitude]), None, 0.0, 1.0
    if isinstance(load, GroundMotion):
        return -mass_full, None, load.accel, 1.0, load.dt
    if isinstance(load, ForceRecord):
        dist = load.distribution
        if len(dist) not in (nf, len(mass_full)):
            raise ParameterError(f"distribution has {len(dist)} entries: give one per floor ({nf}) "
                                 f"or one per floor and damper unit ({len(mass_full)})")
        vec[:len(dist)] = dist
        return vec, None, load.values, 0.0, load.dt
    raise ParameterError(f"load of type {type(load).__name__} is not supported: Harmonic, GroundMotion or ForceRecord")


#: the monitors a run can certify peaks of, by group: the roof (its displacement and absolute acceleration),
#: each storey's drift, each damper's stroke.  A run certifies the groups it is asked for (simulate_scene's
#: `peaks`); the others read NaN and cost nothing but the roof's row, which the window's square reads
PEAK_GROUPS = ("roof", "drifts", "strokes")
#: a group of which a run may ask only the largest peak: its monitors then share one running peak (bundles.
#: MonitorArrays.share), so that a storey's drift below the largest is settled by the largest's bar, searched less
#: and clear of more record steps; each member reads NaN, the result the group's largest (the IDA's ask)
LARGEST_OF = {"largest_drift": "drifts"}


def _monitors(scene: Scene, nfull: int, peaks=PEAK_GROUPS):
    """Rows: roof displacement, roof absolute acceleration, each storey's drift, each damper's stroke.

    Also each row's cap: a bound its peak cannot pass (beyond the contact tolerance).  A stroke between
    walls reaches its cap, half the gap, at the first impact; the kernel stops searching it from then on.  A
    group the run is not asked to certify (`peaks`, of PEAK_GROUPS) has cap 0: the kernel never searches it.
    And each row's share: the first row of a group asked for its largest peak alone (LARGEST_OF), its own index
    otherwise.
    """
    unknown = sorted(set(peaks) - set(PEAK_GROUPS) - set(LARGEST_OF))
    if unknown:
        raise ParameterError(f"peaks: {', '.join(map(repr, unknown))} unknown; allowed "
                             f"{', '.join((*PEAK_GROUPS, *LARGEST_OF))}")
    nf = scene.building.storeys
    rows = []
    kinds = []
    roof = np.zeros(nfull)
    roof[nf - 1] = 1.0
    rows += [roof, roof]
    kinds += [L.MON_DISP, L.MON_ACCEL]
    caps = [math.inf] * (2 + nf)
    for i in range(nf):
        r = np.zeros(nfull)
        r[i] = 1.0
        if i > 0:
            r[i - 1] = -1.0
        rows.append(r)
        kinds.append(L.MON_DISP)
    first = 0
    for d in scene.dampers:
        r = np.zeros(nfull)
        r[nf + first] = 1.0
        r[scene.floor_index(d.floor)] -= 1.0
        rows.append(r)
        kinds.append(L.MON_DISP)
        caps.append(0.5 * d.clearance if d.has_walls else math.inf)
        first += int(d.units)
    caps = np.array(caps)
    for part in _unasked(nf, peaks):
        caps[part] = 0.0
    share = np.arange(len(rows), dtype=np.int64)
    for part in _shared(nf, peaks):
        share[part] = part.start
    return np.array(rows), np.array(kinds, dtype=np.int64), caps, share


def _parts(nf: int) -> dict[str, slice]:
    """Each group's monitors, as _monitors lays them out: the roof's two, the drifts, the strokes."""
    return dict(zip(PEAK_GROUPS, (slice(0, 2), slice(2, 2 + nf), slice(2 + nf, None))))


def _unasked(nf: int, peaks) -> list[slice]:
    """The monitors of the groups of PEAK_GROUPS that `peaks` asks for neither each nor the largest of."""
    asked = {LARGEST_OF.get(name, name) for name in peaks}
    return [part for group, part in _parts(nf).items() if group not in asked]


def _shared(nf: int, peaks) -> list[slice]:
    """The monitors of the groups that `peaks` asks for the largest of alone (each member's peak not asked)."""
    return [_parts(nf)[group] for name, group in LARGEST_OF.items() if name in peaks and group not in peaks]


#: the engine's code of each contact mode of the model (impact.model.scene.CONTACT_MODES), and back
MODE_CODES = {"free": L.MODE_FREE, "held": L.MODE_STUCK, "locked": L.MODE_LOCKED, "floor": L.MODE_FLOOR}
CONTACT_MODE_OF_CODE = {code: mode for mode, code in MODE_CODES.items()}


def contacts_of(rows) -> tuple:
    """Each unit's Contact from the engine's rows (mode code, wall side, slide sign)."""
    return tuple(Contact(CONTACT_MODE_OF_CODE[int(m)], int(side), int(slide)) for m, side, slide in rows)


def _initial_state(scene: Scene, floor: np.ndarray, gap: np.ndarray, kind: np.ndarray, nfull: int):
    if scene.initial is not None:
        return _given_state(scene.initial, gap)
    nf = scene.building.storeys
    q = np.zeros(nfull)
    mode = np.zeros(len(gap), dtype=np.int64)
    side = np.zeros(len(gap), dtype=np.int64)
    for j in range(len(gap)):
        if not kind[j] & L.UNIT_WALLS:
            continue
        if gap[j] == 0.0:
            mode[j] = L.MODE_LOCKED
        elif scene.unit_starts is not None:
            x = scene.unit_starts[j]
            q[nf + j] = x
            if abs(x) == 0.5 * gap[j]:  # on a wall: resting against it, as the protocol's wall starts
                mode[j], side[j] = L.MODE_STUCK, (1 if x > 0 else -1)
        elif scene.start != "centre":
            s = 1 if scene.start == "right" else -1
            q[nf + j] = s * 0.5 * gap[j]
            mode[j] = L.MODE_STUCK
            side[j] = s
    return q, np.zeros(nfull), mode, side


def _given_state(state: State, gap: np.ndarray):
    """A scene's initial State as the loop's start: a unit given 'floor' starts free, and the loop finds at once
    that its floor drags it (no relative velocity, friction), as it does for every unit at rest; a unit with a
    gap of zero is one body with its floor, whatever it is given."""
    mode = np.array([MODE_CODES[c.mode] if c.mode != "floor" else L.MODE_FREE for c in state.contacts],
                    dtype=np.int64)
    mode[gap == 0.0] = L.MODE_LOCKED
    side = np.array([c.side for c in state.contacts], dtype=np.int64)
    return np.array(state.q), np.array(state.v), mode, side


def _cache(nmax: int) -> ConfigCache:
    """An empty cache of CACHE_SLOTS configurations (key -1: not filled); nmax: the largest reduced size."""
    s, m2 = CACHE_SLOTS, 2 * nmax
    return ConfigCache(np.full(s, -1, dtype=np.int64), np.zeros(s, dtype=np.int64),
                       np.zeros((s, m2), dtype=np.complex128), np.zeros((s, m2, m2), dtype=np.complex128),
                       np.zeros((s, m2, m2), dtype=np.complex128), np.zeros((s, nmax, nmax)),
                       np.zeros((s, nmax, nmax)), np.zeros((s, nmax), dtype=np.int64), np.zeros((s, nmax)),
                       np.zeros((s, m2), dtype=np.complex128), np.zeros((s, nmax)))


def _yield_arrays(scene: Scene) -> YieldArrays | None:
    """A yielding building's storey table (bundles.YieldArrays), at rest on its elastic branches; None if elastic."""
    b = scene.building
    if b.is_elastic:
        return None
    nf = b.storeys
    dy = b.yield_drift if b.yield_drift is not None else np.full(nf, np.inf)
    geometric = scene.geometric_stiffness()
    limit = np.full(nf, np.inf)
    if scene.collapse_drift_ratio is not None:
        limit = scene.collapse_drift_ratio * b.storey_height
    zi, zf = np.zeros(nf, dtype=np.int64), np.zeros(nf)
    return YieldArrays(b.storey_stiffness.copy(), np.full(nf, b.hardening), dy.copy(), geometric, limit, zi.copy(),
                       zf.copy(), zi.copy(), zi.copy(), zf.copy(), zi.copy())


def _scene_arrays(scene: Scene, peaks=PEAK_GROUPS, window: bool = True):
    b = scene.building
    omega1 = b.omega1
    kind, floor, mass, gap, e, k, c, a_f = _unit_arrays(scene, omega1)
    nf = b.storeys
    mass_full = np.concatenate([b.masses, mass])
    load_vec, harm, record, mon_rec, rec_dt = _load_arrays(scene, mass_full)
    uload = load_vec[nf:] / mass if len(mass) else np.zeros(0)
    if harm is not None and np.any(uload != 0.0):
        raise ParameterError("a harmonic load acts on a floor, not on a damper unit")
    building = BuildingArrays(b.masses.copy(), b.stiffness, b.damping.copy())
    units = UnitArrays(kind, floor, mass, uload, gap, e)
    springs = SpringArrays(k, c) if np.any(kind & L.UNIT_SPRING) else None
    fric = a_f if np.any(a_f > 0.0) else None
    rows, kinds, caps, share = _monitors(scene, nf + len(mass), peaks)
    monitors = MonitorArrays(rows, kinds, np.where(kinds == L.MON_ACCEL, mon_rec, 0.0), caps, share)
    n_spring = int(np.count_nonzero(kind & L.UNIT_SPRING))
    p = np.zeros(L.NPAR)
    p[L.P_T0] = 0.0
    p[L.P_TEND] = scene.t_end
    p[L.P_TWIN] = scene.t_window
    p[L.P_WINDOW] = 1.0 if window else 0.0
    p[L.P_MAXEV] = scene.max_events_per_period
    p[L.P_MAXEV_RUN] = scene.event_budget
    yld = _yield_arrays(scene)
    # theta = P / (k h) past the model's bound, read off the storey table (its geometric stiffness is P / h)
    p[L.P_FROM_ITSELF] = float(yld is not None and np.any(yld.geometric > MAX_STABILITY * yld.stiffness))
    p[L.P_PERIOD] = 2.0 * math.pi / omega1
    if harm is not None:
        p[L.P_OMEGA] = scene.load.omega
        p[L.P_PHI] = scene.load.phase
        p[L.P_F0] = scene.load.amplitude
        scale = scene.load.amplitude
    else:
        scale = float(np.sum(np.abs(load_vec)) * np.max(np.abs(record)))
    q0, v0, mode0, side0 = _initial_state(scene, floor, gap, kind, nf + len(mass))
    if scale == 0.0:
        p[L.P_VSTICK] = free_vibration_stick(q0, v0, omega1)
    else:
        p[L.P_VSTICK] = STICK_VELOCITY * scale / (float(np.sum(mass_full)) * omega1)
    p[L.P_REC_T0] = 0.0
    p[L.P_REC_DT] = rec_dt
    clear = None
    if record is not None and fric is None and not p[L.P_FROM_ITSELF]:
        # whole record steps by matrices where clear (none past the stability bound, whose rows lose their digits)
        clear = clear_step_tables(building, units, springs, yld, load_vec, rec_dt, monitors)
    return dict(model=SceneArrays(p, building, units, load_vec, monitors), springs=springs, fric=fric, harm=harm,
                record=record, yld=yld, clear=clear, start=StartState(q0, v0, mode0, side0),
                cache=_cache(nf + n_spring))


def run_arrays(arrays: dict, record: int = 0, times=None):
    """Run the kernel on prepared arrays; returns the raw outputs (for benchmarks and tests)."""
    nfull = len(arrays["start"].q)
    nmon = len(arrays["model"].monitors.kind)
    ts = np.asarray(times, dtype=float) if times is not None else np.zeros(0)
    out = RunOutputs(recs=np.zeros((int(record), L.NREC)), diag=np.zeros(L.NDIAG), q=np.zeros(nfull),
                     v=np.zeros(nfull), peak=np.zeros(nmon), peak_t=np.zeros(nmon), x2=np.zeros(nmon),
                     roundoff=np.zeros(nmon), ts=ts,
                     samples=np.zeros((len(ts), 3 * nfull)),
                     contact=np.zeros((len(arrays["start"].mode), 3), dtype=np.int64))
    a = arrays
    cache = ConfigCache(*(c.copy() for c in a["cache"]))
    yld = YieldArrays(*(x.copy() for x in a["yld"])) if a["yld"] is not None else None
    run_scene(a["model"], a["springs"], a["fric"], a["harm"], a["record"], yld, a["clear"], a["start"], cache, out)
    result = out._asdict()
    result["yld"] = yld
    return result


def simulate_scene(scene: Scene, *, record: int = 0, times=None, peaks=PEAK_GROUPS, window: bool = True
                   ) -> SceneResult:
    """Run a scene on the exact core.

    record: keep up to this many impact records; times: sorted times at which
    to sample the state of every degree of freedom (dense output); peaks: the groups of monitors
    (PEAK_GROUPS) whose peaks the run certifies, or whose largest peak alone (LARGEST_OF), the others NaN; window:
    whether the run integrates the roof's square over the window (the amplitude and the RMS, NaN without it).
    """
    arrays = _scene_arrays(scene, peaks, window)
    key = _signature_key(arrays)
    if key not in _WARM:
        with compile_lock(_kernel_name(key), _kernel_label(key), fresh=(run_scene,)):
            out = run_arrays(arrays, record, times)
        _WARM.add(key)
    else:
        out = run_arrays(arrays, record, times)
    return _result(scene, arrays, out, peaks, window)


_WARM: set = set()  # the loops' specialisations compiled (or loaded) in this process


#: the optional parts of a scene, each compiled into its own specialisation of the loop when present
OPTIONAL_PARTS = {"springs": "pendulums or TMDs", "fric": "friction", "harm": "a harmonic load",
                  "record": "a load record", "yld": "yielding storeys", "clear": "whole record steps by matrices"}


def _signature_key(arrays: dict) -> tuple:
    return tuple(arrays[k] is None for k in OPTIONAL_PARTS)


def _kernel_name(key: tuple) -> str:
    return "scene-" + "".join("0" if absent else "1" for absent in key)


def _kernel_label(key: tuple) -> str:
    parts = [text for text, absent in zip(OPTIONAL_PARTS.values(), key) if not absent]
    return "the engine's scene loop" + (f" for scenes with {', '.join(parts)}" if parts else "")


def _result(scene: Scene, arrays: dict, out: dict, groups=PEAK_GROUPS, window: bool = True) -> SceneResult:
    nf = scene.building.storeys
    diag = out["diag"]
    span = diag[L.D_TEND] - scene.t_window
    collapsed = bool(diag[L.D_COLLAPSE])
    # a collapse ends the run on purpose: its peaks up to the collapse stand, its window's rms does not
    complete = not diag[L.D_CAP] and (span > 0 or collapsed)
    rms = math.sqrt(out["x2"][0] / span) if window and complete and not collapsed else math.nan
    records = None
    if out["recs"].shape[0]:
        n = int(diag[L.D_NREC])
        records = {c: out["recs"][:n, i].copy() for i, c in enumerate(L.RECORD_COLUMNS)}
    samples = None
    if len(out["ts"]):
        nfull = len(out["q"])
        dense = out["samples"]
        samples = {"t": out["ts"], "q": dense[:, :nfull], "v": dense[:, nfull:2 * nfull],
                   "q_roundoff": dense[:, 2 * nfull:]}
    peaks, roundoff = out["peak"].copy(), out["roundoff"].copy()
    for part in _unasked(nf, groups):
        peaks[part] = math.nan
        roundoff[part] = math.nan
    parts = _parts(nf)
    drifts, strokes = parts["drifts"], parts["strokes"]
    largest_drift = float(np.max(peaks[drifts])) if complete else math.nan
    for part in _shared(nf, groups):  # a member holds the group's largest, not its own peak
        peaks[part] = math.nan
        roundoff[part] = math.nan
    return SceneResult(
        scene=scene,
        peak_roof_displacement=float(peaks[0]) if complete else math.nan,
        peak_roof_displacement_time=float(out["peak_t"][0]) if "roof" in groups else math.nan,
        rms_roof_displacement=rms,
        peak_roof_acceleration=float(peaks[1]) if complete else math.nan,
        peak_interstorey_drift=largest_drift,
        peak_drifts=peaks[drifts].copy(),
        peak_strokes=peaks[strokes].copy(),
        impacts=int(diag[L.D_IMPACTS]),
        diagnostics=read_diagnostics(diag),
        final_q=out["q"].copy(),
        final_v=out["v"].copy(),
        records=records,
        samples=samples,
        amplitude=math.sqrt(2.0) * rms,
        window_span=float(span),
        storeys=_storey_response(scene, out["yld"], peaks[drifts], collapsed),
        final_contacts=contacts_of(out["contact"]),
        peak_roundoff=roundoff,
    )


def _storey_response(scene: Scene, yld: YieldArrays | None, peak_drifts: np.ndarray, collapsed: bool):
    """The storeys' measures from the run's yield table (None for an elastic building)."""
    if yld is None:
        return None
    b = 1.0 - yld.hardening
    p = yld.offset
    elastic = yld.stiffness - yld.geometric
    with np.errstate(divide="ignore", invalid="ignore"):
        rest = np.where(elastic > 0.0, b * yld.stiffness * p / elastic, np.nan)
    rest[np.abs(rest - p) > yld.yield_drift] = np.nan
    return StoreyResponse(peak_drifts=peak_drifts.copy(), plastic_offsets=p.copy(), residual_drifts=rest,
                          ductility=peak_drifts / yld.yield_drift, yield_events=yld.yields.copy(),
                          plastic_work=float(np.sum(yld.plastic)), collapsed=collapsed,
                          has_rest=bool(np.all(np.isfinite(rest))))


def amplitude(result: SceneResult) -> float:
    """The paper's amplitude sqrt(2) RMS of the roof over the window."""
    return result.amplitude


def warm_up_scenes(yielding: tuple[bool, ...] = (False,)) -> list[Scene]:
    """One short scene of each specialisation of the scene loop the study runs: on elastic buildings every one
    (OPTIONAL_PARTS: with and without pendulums, friction, a harmonic load), on yielding ones those of the collapse
    stage (a record, no friction, with and without pendulums), and every one of those too with `yielding` holding
    True (the random scene probe draws them).  Running each compiles it into numba's cache."""
    building = Building.uniform(1, 1.0, 0.05)
    mass = 0.02 * building.total_mass
    loads = (Harmonic(1e3, building.omega1), GroundMotion(np.array([0.0, 1.0, -1.0, 0.0]), 0.1))
    # a kind whose mass slides between walls, and one with a spring between walls: the registry's, not named here
    sliding = next(name for name, kind in KINDS.items() if kind.slides and kind.walls)
    sprung = next(name for name, kind in KINDS.items() if kind.spring and kind.walls)
    every = itertools.product((False, True), (False, True), loads, yielding)
    collapse = () if True in yielding else itertools.product((False, True), (False,), loads[1:], (True,))
    scenes = []
    for springs, friction, load, yields in itertools.chain(every, collapse):
        dampers = [Damper(sliding, mass, gap=0.01, e=0.5, nu=0.1 if friction else 0.0)]
        if springs:
            dampers.append(Damper(sprung, mass, gap=0.01, e=0.5))
        built = building.yielding(0.01, 0.1) if yields else building
        scenes.append(Scene(built, tuple(dampers), load, duration=0.5))
    return scenes


def compile_scene_loops(yielding: tuple[bool, ...] = (False,)) -> None:
    """Compile the specialisations of the scene loop the study runs (:func:`warm_up_scenes`) into numba's cache."""
    for scene in warm_up_scenes(yielding):
        simulate_scene(scene)
