"""Runs and frequency sweeps of the CID and PID with the exact event-driven core.

`simulate` follows the paper's response protocol (model.md): start from rest
(damper mass centred or at a wall), simulate `periods` natural periods, and
measure the amplitude as sqrt(2) * RMS of x over the window from
`average_from` periods on, integrated exactly from the piecewise closed form.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from impact.engine import layout as L
from impact.engine import paper_loop as K
from impact.engine.contact import STICK_VELOCITY
from impact.engine.diagnostics import read_diagnostics
from impact.engine.jitcache import compile_lock
from impact.model.kinds import KINDS
from impact.model.params import Protocol, System, ipc_class, ipc_label

_WARM: set = set()
FREE_FLIGHT = K.contact_code(L.MODE_FREE, 0, 0)


def ensure_compiled(kind: str, friction: bool = False) -> None:
    """Compile (or load from numba's on-disk cache) the kernel for one damper kind, under compile_lock."""
    key = (kind, friction)
    if key in _WARM:
        return
    label = f"the engine's paper loop for the {kind.upper()}" + (" with friction" if friction else "")
    with compile_lock(f"paper-{kind}-{int(friction)}", label, fresh=(K.run,)):
        probe = System(kind, mu=0.01, beta=0.05, e=0.5, gap=1.0, rp=1.0 if KINDS[kind].spring else 0.0,
                       nu=0.1 if friction else 0.0)
        _run_kernel(probe, 0.9, Protocol(periods=1.0, average_from=0.5), np.zeros(4), FREE_FLIGHT, 1)
    _WARM.add(key)


def pid_data(system: System, r: float):
    """Eigen-data of the PID's free flight and the harmonic particular solution.

    State (x, x', y, y'): x'' = -2 beta x' - x + mu wp^2 (y - x) + f sin, y'' = -wp^2 (y - x).
    Returns None for the CID, so the kernel compiles without the pendulum path.
    """
    if not KINDS[system.kind].spring:
        return None
    mu, b, wp2 = system.mu, system.beta, system.rp ** 2
    a = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [-(1.0 + mu * wp2), -2.0 * b, mu * wp2, 0.0],
        [0.0, 0.0, 0.0, 1.0],
        [wp2, 0.0, -wp2, 0.0],
    ])
    lam, vec = np.linalg.eig(a)
    vec = vec.astype(np.complex128)
    vinv = np.linalg.inv(vec)
    forcing = np.array([0.0, system.force_ratio, 0.0, 0.0], dtype=np.complex128)
    zc = np.linalg.solve(1j * r * np.eye(4) - a, forcing)
    return (lam.astype(np.complex128), vec, vinv, zc)


def initial_state(system: System, start: str):
    """Rest, with the damper mass centred or resting against a wall.

    Returns (state, contact code); a mass placed at a wall starts in contact
    and the kernel decides at once whether the wall holds it.
    """
    half = 0.5 * system.gap
    if start == "centre" or system.gap == 0.0:
        return np.zeros(4), FREE_FLIGHT
    side = 1 if start == "right" else -1
    return np.array([0.0, 0.0, side * half, 0.0]), K.contact_code(L.MODE_STUCK, side, 0)


def check_resonance(system: System, r: float):
    if system.beta == 0.0 and abs(r - 1.0) < 1e-12:
        raise ValueError("r = 1 with beta = 0 is the undamped resonance: the forced response is unbounded")


def param_vector(system: System, r: float, protocol: Protocol, t0: float = 0.0) -> np.ndarray:
    """The paper loop's parameter vector (layout.P_*, NPAR_PAPER of them) of one run under the protocol."""
    return run_parameters(system, r, protocol.t_end, protocol.t_window, protocol.max_events_per_period, t0)


def run_parameters(system: System, r: float, t_end: float, t_window: float, max_events_per_period: int,
                   t0: float = 0.0, max_events: float = math.inf) -> np.ndarray:
    """param_vector with the run's times given (a scene carries them, not a Protocol).  max_events: the run's
    event budget (a scene's; a protocol's run is bounded by its periods and its cap per period)."""
    p = np.zeros(L.NPAR_PAPER)
    p[L.P_MU] = system.mu
    p[L.P_BETA] = system.beta
    p[L.P_E] = system.e
    p[L.P_GAP] = system.gap
    p[L.P_WP] = system.rp
    p[L.P_F0] = system.force_ratio
    p[L.P_OMEGA] = r
    p[L.P_PHI] = system.phase
    p[L.P_VSTICK] = STICK_VELOCITY * system.force_ratio
    p[L.P_TEND] = t_end
    p[L.P_TWIN] = t_window
    p[L.P_MAXEV] = max_events_per_period
    p[L.P_MAXEV_RUN] = max_events
    p[L.P_T0] = t0
    p[L.P_PERIOD] = 2.0 * math.pi  # the event cap counts per natural period
    return p


@dataclass
class RunResult:
    """One run under the response protocol (model units)."""

    r: float
    amplitude: float
    amplitude_ratio: float
    aipc: float
    ipc_class: int
    diagnostics: dict
    final_state: np.ndarray
    final_contact: int
    records: dict | None = field(default=None, repr=False)

    def as_json(self) -> dict:
        out = {
            "r": self.r,
            "amplitude": self.amplitude,
            "amplitude_ratio": self.amplitude_ratio,
            "aipc": self.aipc,
            "ipc_class": ipc_label(self.aipc),
            "diagnostics": self.diagnostics,
        }
        return out


def simulate(system: System, r: float, protocol: Protocol = Protocol(), *, record: int = 0,
             state=None, contact=None, t0: float = 0.0) -> RunResult:
    """One run at frequency ratio r.

    record: keep up to this many impact records (t, side, x, v-, y'-, v+, y'+, stuck).
    state/contact: start from a given (x, x', y, y') and contact code instead of
    the protocol's rest state (continuation sweeps, closed-form orbits).
    """
    check_resonance(system, r)
    if state is None:
        z0, code = initial_state(system, protocol.start)
    else:
        z0 = np.asarray(state, dtype=float)
        code = FREE_FLIGHT if contact is None else int(contact)
    ensure_compiled(system.kind, system.nu > 0.0)
    return _run_kernel(system, r, protocol, z0, code, record, t0)


def friction_data(system: System):
    """(a_f,) in model units, or None: a frictionless run never compiles the friction path."""
    return np.array([system.friction_accel]) if system.nu > 0.0 else None


def _run_kernel(system, r, protocol, z0, code, record, t0=0.0) -> "RunResult":
    p = param_vector(system, r, protocol, t0)
    rec = np.zeros((int(record), L.NREC))
    diag = np.zeros(L.NDIAG)
    z_out = np.zeros(4)
    final = K.run(p, np.asarray(z0, dtype=float), int(code), pid_data(system, r), friction_data(system),
                  rec, diag, z_out)
    return _result(system, r, protocol, diag, z_out, final, rec)


def window_amplitude(diag, t_window: float) -> tuple[float, float, bool]:
    """(amplitude sqrt(2) RMS of x over the window, the window's span, whether the run completed it) from a
    paper-loop run's diagnostics: the one place this is computed, so every caller gets the same bits."""
    span = diag[L.D_TEND] - t_window
    complete = bool(not diag[L.D_CAP] and span > 0)
    return (math.sqrt(2.0 * diag[L.D_X2WIN] / span) if complete else math.nan), span, complete


def _result(system, r, protocol, diag, z_out, final, rec) -> RunResult:
    amp, span, complete = window_amplitude(diag, protocol.t_window)
    cycles = span * r / (2.0 * math.pi)
    aipc = diag[L.D_IMPACTS_WIN] / cycles if complete else math.nan
    records = None
    if rec.shape[0]:
        n = int(diag[L.D_NREC])
        records = {c: rec[:n, i].copy() for i, c in enumerate(L.RECORD_COLUMNS)}
    amax = system.a_max
    return RunResult(
        r=float(r),
        amplitude=amp,
        amplitude_ratio=amp / amax if math.isfinite(amax) else math.nan,
        aipc=aipc,
        ipc_class=ipc_class(aipc),
        diagnostics=read_diagnostics(diag),
        final_state=z_out.copy(),
        final_contact=int(final),
        records=records,
    )


@dataclass
class SweepResult:
    """A frequency sweep under the protocol: per-r results and the paper's x_max, X_m."""

    r: np.ndarray
    runs: list

    def column(self, name: str) -> np.ndarray:
        if name in ("amplitude", "amplitude_ratio", "aipc", "ipc_class"):
            return np.array([getattr(run, name) for run in self.runs])
        return np.array([run.diagnostics[name] for run in self.runs])

    @property
    def x_max(self) -> float:
        amp = self.column("amplitude")
        return float(np.max(amp)) if np.all(np.isfinite(amp)) else math.nan

    @property
    def r_at_max(self) -> float:
        amp = self.column("amplitude")
        return float(self.r[int(np.nanargmax(amp))]) if np.any(np.isfinite(amp)) else math.nan


SWEEP_MODES = ("from_rest", "continuation_up", "continuation_down")


def _progress(values, show: bool):
    """values, with a progress bar on stderr when asked and stderr is a terminal (tqdm: silent otherwise)."""
    if not show:
        return values
    from tqdm import tqdm

    return tqdm(values, desc="frequencies", unit="run", leave=False, disable=None)


def sweep(system: System, r_values, protocol: Protocol = Protocol(), mode: str = "from_rest",
          state=None, contact=None, progress: bool = False) -> SweepResult:
    """Frequency sweep under the protocol.

    from_rest: every frequency starts afresh from the protocol's start (or from
    `state`/`contact` when given: one initial condition for every frequency).
    continuation_up / _down: frequencies in increasing / decreasing order, each
    starting from the final state of the previous one, as a slow physical
    sweep would; the force stays continuous (its phase carries over).  Each
    frequency still runs the protocol's periods and window, so the first
    average_from periods settle the new frequency.  Results are in the order
    of r_values either way.  progress: a progress bar on stderr when it is a terminal (tqdm).
    """
    if mode not in SWEEP_MODES:
        raise ValueError(f"sweep mode {mode!r} is not one of {', '.join(SWEEP_MODES)}")
    r_values = np.asarray(r_values, dtype=float)
    if mode == "from_rest":
        runs = [simulate(system, float(r), protocol, state=state, contact=contact)
                for r in _progress(r_values, progress)]
        return SweepResult(r=r_values, runs=runs)
    order = np.argsort(r_values, kind="stable")
    if mode == "continuation_down":
        order = order[::-1]
    runs = [None] * len(r_values)
    current, z, code = system, state, contact
    for i in _progress(order, progress):
        r = float(r_values[i])
        run = simulate(current, r, protocol, state=z, contact=code)
        runs[i] = run
        z, code = run.final_state, run.final_contact
        # the force phase at the end of this run is the next run's phase at t = 0
        end_phase = math.remainder(r * protocol.t_end + current.phase, 2.0 * math.pi)
        current = dataclasses.replace(current, phase=end_phase)
    return SweepResult(r=r_values, runs=runs)
