"""The model side of the cross-validation: Eq. (4) of the paper, sampled into records.

Eq. (4) -- a linear pendulum, instantaneous Newton impacts -- is run by the production exact
event-driven kernel (:mod:`impact.engine.paper_loop`, model units M = 1, omega = 1, lengths in mm) and
sampled at the sensor's rate into records of the experiment data format (``synthetic: true``),
so that it goes through the same analysis code as the rig's records (:mod:`.comparison`).  The
bare structure (mu = 0) is its exact closed form.
"""

from __future__ import annotations

import math
from collections import namedtuple
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from impact.engine import layout as L
from impact.engine import paper_loop as K
from impact.engine.contact import STICK_VELOCITY
from impact.engine.jitcache import compile_lock
from impact.engine.paper import ensure_compiled, initial_state, pid_data
from impact.engine.paper import param_vector as model_param_vector
from impact.engine.sampler import paper_free_flight, paper_state
from impact.model.kinds import PID
from impact.model.params import Protocol, System
from impact.outputs.measurements import Measurement, make_measurement
from impact.rig import simulator as R
from impact.rig.config import validation_config
from impact.stages.validation.grid import Case, wall_e

# one call of the paper loop: its parameters, the PID's eigen-data, and where it writes (records, diagnostics,
# the final state); and the sample times with the arrays they fill (x and the stroke s = y - x)
PaperCall = namedtuple("PaperCall", "p pid rec diag z_out")
Samples = namedtuple("Samples", "ts xs ss")

MODEL_SOURCE = ("model: Eq. (4) of the paper (linear pendulum, instantaneous impacts) simulated by the "
                "production exact event-driven kernel impact.engine.paper_loop.run; synthetic")


def model_system(cfg: dict, case: Case) -> System:
    """Eq. (4) in model units (M = 1, omega = 1, lengths in mm) for a case."""
    return System(kind=PID, mu=case.mu, beta=float(cfg["structure"]["beta"]), e=wall_e(cfg, case.wall),
                  gap=case.gap_mm, rp=case.rp, force_ratio=float(cfg["excitation"]["force_ratio_mm"]),
                  phase=float(cfg["excitation"].get("phase", 0.0)),
                  frequency_hz=float(cfg["structure"]["frequency_hz"]), unit_m=1e-3)


@njit(cache=True)
def _model_chunk_dense(call, z, code, ta, tb, samples, i0, i1):
    """One call of the production kernel over [ta, tb]; samples ts[i0:i1] in (ta, tb] rebuilt from its events.

    Between impacts the kernel's motion is the closed-form free flight from
    the post-impact state (the kernel's own closed form, through the public
    sampler :mod:`impact.engine.sampler`), so the samples are exact.  Returns (new code, ok): ok = False
    when the chunk contains a sticking episode (a release is not recorded) or
    more impacts than ``rec`` holds -- then the caller re-runs it sample by
    sample.
    """
    p, pid, rec, diag = call.p, call.pid, call.rec, call.diag
    ts, xs, ss = samples
    p[L.P_T0] = ta
    p[L.P_TEND] = tb
    code_new = K.run(p, z, code, pid, None, rec, diag, call.z_out)
    nr = int(diag[L.D_NREC])
    if code % 10 != L.MODE_FREE or nr >= rec.shape[0] or diag[L.D_CAP] > 0.0:
        return code_new, False
    for j in range(nr):
        if rec[j, L.R_STUCK] > 0.0:
            return code_new, False
    kap = np.zeros(K.NT, dtype=np.complex128)
    cx = np.zeros(K.NT, dtype=np.complex128)
    cy = np.zeros(K.NT, dtype=np.complex128)
    poly = np.zeros(2)
    zs = z.copy()
    zt = np.zeros(4)
    t_seg = ta
    half = 0.5 * p[L.P_GAP]
    j = 0
    paper_free_flight(kap, cx, cy, poly, zs, t_seg, p, pid)
    for i in range(i0, i1):
        while j < nr and rec[j, L.R_T] <= ts[i]:
            side = rec[j, L.R_SIDE]
            zs[0] = rec[j, L.R_X]
            zs[1] = rec[j, L.R_V1]
            zs[2] = rec[j, L.R_X] + side * half
            zs[3] = rec[j, L.R_W1]
            t_seg = rec[j, L.R_T]
            paper_free_flight(kap, cx, cy, poly, zs, t_seg, p, pid)
            j += 1
        paper_state(kap, cx, cy, poly, ts[i] - t_seg, zt)
        xs[i] = zt[0]
        ss[i] = zt[2] - zt[0]
    return code_new, True


@njit(cache=True)
def _advance(call, z, code, ta, tb):
    """One kernel call from ta to tb, the state moved to tb; returns (contact code, capped)."""
    p, diag = call.p, call.diag
    p[L.P_T0] = ta
    p[L.P_TEND] = tb
    code = K.run(p, z, code, call.pid, None, call.rec, diag, call.z_out)
    capped = diag[L.D_CAP] > 0.0 or diag[L.D_TEND] < tb
    for k in range(4):
        z[k] = call.z_out[k]
    return code, capped


@njit(cache=True)
def _keep_impacts(rec, diag, imp, nimp):
    """Append the call's impact records (time, wall) to imp while it has room; returns the new count."""
    for j in range(int(diag[L.D_NREC])):
        if nimp < imp.shape[0]:
            imp[nimp, 0] = rec[j, L.R_T]
            imp[nimp, 1] = rec[j, L.R_SIDE]
        nimp += 1
    return nimp


@njit(cache=True)
def _model_samples(call, z0, code0, t0, samples, imp, out, chunk):
    """Run the production kernel from t0 through the sample times ts (model units).

    The kernel runs over chunks of ``chunk`` samples; inside a chunk the
    samples are rebuilt exactly from its impact records
    (:func:`_model_chunk_dense`), or -- if the chunk holds a sticking episode
    -- by one kernel call per sample interval.  x and s = y - x at every
    sample; impact times and walls into imp; out = (impacts, event cap
    reached, final contact code).
    """
    rec, diag, zo = call.rec, call.diag, call.z_out
    ts, xs, ss = samples
    z = z0.copy()
    code = code0
    t = t0
    nimp = 0
    cap = 0.0
    n = ts.shape[0]
    i = 0
    # samples at t0
    while i < n and ts[i] <= t:
        xs[i] = z[0]
        ss[i] = z[2] - z[0]
        i += 1
    if i < n and ts[i] > t:
        # settle: one call up to the first sample
        code, capped = _advance(call, z, code, t, ts[i])
        if capped:
            cap = 1.0
        t = ts[i]
        xs[i] = z[0]
        ss[i] = z[2] - z[0]
        i += 1
    while i < n:
        i1 = min(i + chunk, n)
        tb = ts[i1 - 1]
        code_new, ok = _model_chunk_dense(call, z, code, t, tb, samples, i, i1)
        if ok:
            nimp = _keep_impacts(rec, diag, imp, nimp)
            code = code_new
            for k in range(4):
                z[k] = zo[k]
            t = tb
        else:
            # sample by sample from the chunk's start
            for ii in range(i, i1):
                if ts[ii] > t:
                    code, capped = _advance(call, z, code, t, ts[ii])
                    nimp = _keep_impacts(rec, diag, imp, nimp)
                    if capped:
                        cap = 1.0
                    t = ts[ii]
                xs[ii] = z[0]
                ss[ii] = z[2] - z[0]
        i = i1
    out[0] = nimp
    out[1] = cap
    out[2] = code


@dataclass
class ModelRun:
    t_s: np.ndarray
    x_mm: np.ndarray
    s_mm: np.ndarray
    impact_times_s: np.ndarray
    capped: bool


def _run_model(cfg: dict, case: Case, r: float, ts_s: np.ndarray, *, forced: bool, x0_mm: float = 0.0,
               chunk: int | None = None) -> ModelRun:
    warm_up_model()
    return _sample_model(cfg, case, r, ts_s, forced=forced, x0_mm=x0_mm, chunk=chunk)


def _sample_model(cfg: dict, case: Case, r: float, ts_s: np.ndarray, *, forced: bool, x0_mm: float = 0.0,
                  chunk: int | None = None) -> ModelRun:
    system = model_system(cfg, case)
    omega = 2.0 * math.pi * float(cfg["structure"]["frequency_hz"])
    prot = Protocol(periods=1.0, average_from=0.0)
    p = model_param_vector(system, r, prot)
    p[L.P_TWIN] = 0.0
    data = pid_data(system, r)
    if forced:
        z0, code = initial_state(system, "centre")
    else:
        lam, vec, vinv, zc = data
        data = (lam, vec, vinv, np.zeros_like(zc))
        p[L.P_F0] = 0.0
        p[L.P_VSTICK] = STICK_VELOCITY * max(abs(x0_mm), 1e-6)
        z0 = np.array([x0_mm, 0.0, x0_mm, 0.0])
        code = K.contact_code(L.MODE_FREE, 0, 0)
    tm = np.ascontiguousarray(ts_s * omega)
    xs = np.empty(tm.size)
    ss = np.empty(tm.size)
    imp = np.zeros((200000, 2))
    out = np.zeros(3)
    # settle: one kernel call up to the first sample, then chunks of about one forcing period
    if chunk is None:
        per_cycle = float(cfg["sensor"]["sample_rate_hz"]) / (r * float(cfg["structure"]["frequency_hz"]))
        chunk = max(1, int(round(per_cycle)))
    call = PaperCall(p, data, np.zeros((512, L.NREC)), np.zeros(L.NDIAG), np.zeros(4))
    _model_samples(call, np.asarray(z0, dtype=float), int(code), 0.0, Samples(tm, xs, ss), imp, out, chunk)
    n = int(min(out[0], imp.shape[0]))
    return ModelRun(ts_s, xs, ss, imp[:n, 0] / omega, bool(out[1]))


def _model_header(cfg: dict, case: Case | None, kind: str, notes: str) -> dict:
    fs = float(cfg["sensor"]["sample_rate_hz"])
    hdr: dict[str, Any] = {"format_version": 1, "kind": kind, "synthetic": True, "sample_rate_hz": fs,
                           "units": "mm", "damper": "none" if case is None else PID,
                           "structure_hz": float(cfg["structure"]["frequency_hz"]), "noise_rms": 0.0,
                           "source": MODEL_SOURCE}
    if case is not None:
        hdr.update(mu=case.mu, gap_mm=case.gap_mm, rp=case.rp, wall=case.wall, e=wall_e(cfg, case.wall),
                   ball_diameter_mm=R.diameter_for_mu(cfg, case.mu))
    hdr["notes"] = notes
    return hdr


def _window_times(cfg: dict, periods: float, average_from: float) -> np.ndarray:
    T = 1.0 / float(cfg["structure"]["frequency_hz"])
    fs = float(cfg["sensor"]["sample_rate_hz"])
    n0 = int(math.ceil(average_from * T * fs - 1e-9))
    n1 = int(math.floor(periods * T * fs - 1e-9))
    return np.arange(n0, n1 + 1) / fs


def model_forced_point(cfg: dict, case: Case, r: float) -> tuple[Measurement, ModelRun]:
    """The model's ``forced_sweep_point`` record at r: from rest, the protocol's window sampled."""
    prot = cfg["protocol"]
    ts = _window_times(cfg, prot["periods"], prot["average_from"])
    run = _run_model(cfg, case, r, ts, forced=True)
    if run.capped:
        raise RuntimeError(f"model run hit the event cap at {case.id} r={r}")
    hdr = _model_header(cfg, case, "forced_sweep_point",
                        f"from rest, {prot['periods']:g} periods, window from {prot['average_from']:g}; "
                        f"F0/K = {cfg['excitation']['force_ratio_mm']:g} mm")
    hdr["r"] = float(r)
    hdr["forcing_hz"] = float(r) * float(cfg["structure"]["frequency_hz"])
    return make_measurement(hdr, {"t_s": ts, "x": run.x_mm, "s": run.s_mm}), run


def model_free_decay(cfg: dict, case: Case, x0_mm: float, duration_s: float) -> tuple[Measurement, ModelRun]:
    """The model's ``free_decay`` record: released from x0 with the pendulum hanging at rest."""
    fs = float(cfg["sensor"]["sample_rate_hz"])
    ts = np.arange(int(math.floor(duration_s * fs)) + 1) / fs
    run = _run_model(cfg, case, 1.0, ts, forced=False, x0_mm=x0_mm)
    if run.capped:
        raise RuntimeError(f"model free decay hit the event cap at {case.id} x0={x0_mm}")
    hdr = _model_header(cfg, case, "free_decay", "released from rest, pendulum hanging")
    hdr["x0_mm"] = float(x0_mm)
    return make_measurement(hdr, {"t_s": ts, "x": run.x_mm, "s": run.s_mm}), run


def sdof_response(t_s: np.ndarray, cfg: dict, r: float | None, x0_mm: float = 0.0) -> np.ndarray:
    """Exact response (mm) of the bare structure (Eq. 4 with mu = 0) from rest / from x0.

    r = None: free decay from x0; otherwise forced from rest at ratio r.
    """
    beta = float(cfg["structure"]["beta"])
    w = 2.0 * math.pi * float(cfg["structure"]["frequency_hz"])
    wd = w * math.sqrt(1.0 - beta**2)
    x0, v0 = x0_mm, 0.0
    xp = np.zeros_like(t_s)
    if r is not None:
        fr = float(cfg["excitation"]["force_ratio_mm"])
        phi = float(cfg["excitation"].get("phase", 0.0))
        big_x = fr / complex(1.0 - r * r, 2.0 * beta * r)
        xp = (big_x * np.exp(1j * (r * w * t_s + phi))).imag
        x0 = x0 - (big_x * np.exp(1j * phi)).imag
        v0 = v0 - (big_x * 1j * r * w * np.exp(1j * phi)).imag
    s = beta * w
    a = x0
    b = (v0 + s * x0) / wd
    return np.exp(-s * t_s) * (a * np.cos(wd * t_s) + b * np.sin(wd * t_s)) + xp


def model_bare_forced_point(cfg: dict, r: float, settle_periods: float, record_periods: float) -> Measurement:
    """Bare structure, exact closed form, sampled over the recording window."""
    ts = _window_times(cfg, settle_periods + record_periods, settle_periods)
    hdr = _model_header(cfg, None, "forced_sweep_point",
                        f"bare structure, exact SDOF from rest, window {settle_periods:g} ... "
                        f"{settle_periods + record_periods:g} periods")
    hdr["source"] = "model: Eq. (4) with mu = 0 (linear SDOF), exact closed form; synthetic"
    hdr["r"] = float(r)
    hdr["forcing_hz"] = float(r) * float(cfg["structure"]["frequency_hz"])
    return make_measurement(hdr, {"t_s": ts, "x": sdof_response(ts, cfg, r)})


def model_bare_free_decay(cfg: dict, x0_mm: float, duration_s: float) -> Measurement:
    fs = float(cfg["sensor"]["sample_rate_hz"])
    ts = np.arange(int(math.floor(duration_s * fs)) + 1) / fs
    hdr = _model_header(cfg, None, "free_decay", "bare structure, exact SDOF free decay")
    hdr["source"] = "model: Eq. (4) with mu = 0 (linear SDOF), exact closed form; synthetic"
    hdr["x0_mm"] = float(x0_mm)
    return make_measurement(hdr, {"t_s": ts, "x": sdof_response(ts, cfg, None, x0_mm)})


_WARM = False  # the model sampler compiled (or loaded) in this process


def warm_up_model():
    """Compile (or load) the model sampler, under the engine's one compile lock."""
    global _WARM
    if _WARM:
        return

    ensure_compiled(PID)
    with compile_lock("experiment-model", "the virtual rig's model sampler", fresh=(_model_samples,)):
        cfg = validation_config(None)
        _sample_model(cfg, Case(0.0129, 30.0, 1.0, "steel"), 1.0, np.array([0.0, 0.01]), forced=True)
    _WARM = True
