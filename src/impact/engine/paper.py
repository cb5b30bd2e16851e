"""The paper loop's side of the paper's system (:class:`impact.model.params.System`): its compile, its
parameter vector, the PID's eigen-data, the protocol's rest starts and the window's amplitude.

Runs and sweeps under the paper's response protocol (model.md: start from rest, the damper mass centred or at
a wall, simulate `periods` natural periods, the amplitude sqrt(2) RMS of x over the window from `average_from`
periods on) are :func:`impact.engine.run.simulate_system` and :func:`impact.engine.run.sweep`, which build a
Scene and send it through the engine's dispatch; the dispatch runs it here (``run._run_paper``).
"""

from __future__ import annotations

import math

import numpy as np

from impact.engine import layout as L
from impact.engine import paper_loop as K
from impact.engine import sampler as S
from impact.engine.bundles import PaperCall
from impact.engine.contact import STICK_VELOCITY
from impact.engine.jitcache import compile_lock
from impact.model.kinds import KINDS, kinds_with
from impact.model.params import Protocol, System

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
        p = param_vector(probe, 0.9, Protocol(periods=1.0, average_from=0.5))
        fric = np.array([probe.friction_accel]) if friction else None
        K.run(p, np.zeros(4), FREE_FLIGHT, pid_data(probe, 0.9), fric, np.zeros((1, L.NREC)), np.zeros(L.NDIAG),
              np.zeros(4))
    _WARM.add(key)


def ensure_sampler_compiled() -> None:
    """Compile (or load) the paper loop's dense output (sampler.paper_samples, for each kind the paper loop runs),
    under compile_lock."""
    if "samples" in _WARM:
        return
    for kind in kinds_with("paper"):
        ensure_compiled(kind)  # the loop it calls, under the lock of its own
    with compile_lock("paper-samples", "the paper loop's dense output", fresh=(S.paper_samples,)):
        for kind in kinds_with("paper"):
            probe = System(kind, mu=0.01, beta=0.05, e=0.5, gap=1.0, rp=1.0 if KINDS[kind].spring else 0.0)
            dense_samples(param_vector(probe, 0.9, Protocol(periods=1.0, average_from=0.0)), pid_data(probe, 0.9),
                          np.zeros(4), FREE_FLIGHT, np.array([0.0, 0.5, 1.0]), 2, 1)
    _WARM.add("samples")


def dense_samples(p: np.ndarray, pid, z0, code: int, times: np.ndarray, chunk: int, record: int):
    """The paper loop's dense output (sampler.paper_samples) from p[P_T0] through the sorted times: (the state
    (x, x', y, y') at each time, the impact records kept (up to `record`), the impacts in all, whether the event
    guard stopped a call, the final contact code, the final state)."""
    call = PaperCall(p, pid, np.zeros((512, L.NREC)), np.zeros(L.NDIAG), np.zeros(4))
    z = np.array(z0, dtype=float)
    zs = np.empty((len(times), 4))
    kept = np.zeros((int(record), L.NREC))
    out = np.zeros(3)
    S.paper_samples(call, z, int(code), float(p[L.P_T0]), np.ascontiguousarray(times, dtype=float), zs, kept, out,
                    int(chunk))
    n = int(out[0])
    return zs, kept[:min(n, kept.shape[0])], n, bool(out[1]), int(out[2]), z


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
    # no force (a free decay): no particular solution, exactly
    zc = np.linalg.solve(1j * r * np.eye(4) - a, forcing) if system.force_ratio else np.zeros(4, np.complex128)
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


def window_amplitude(diag, t_window: float) -> tuple[float, float, bool]:
    """(amplitude sqrt(2) RMS of x over the window, the window's span, whether the run completed it) from a
    paper-loop run's diagnostics: the one place this is computed, so every caller gets the same bits."""
    span = diag[L.D_TEND] - t_window
    complete = bool(not diag[L.D_CAP] and span > 0)
    return (math.sqrt(2.0 * diag[L.D_X2WIN] / span) if complete else math.nan), span, complete
