"""Cross-validation of the Eq. (4) model against the virtual rig (the paper's Sect. 3, Figs. 3--5).

For every case of the paper's experimental grid (mu x d x r' x wall, 108
cases) the **model** -- Eq. (4) as simulated by the production exact
event-driven kernel (:mod:`impact.simulate` / :mod:`impact._kernels`: linear
pendulum, instantaneous Newton impacts, model units M = 1, omega = 1, lengths
in mm) -- and the **virtual rig** (:mod:`impact.experiment.rig`: nonlinear
compound pendulum, finite ball, Hunt--Crossley contact calibrated to e, sensor
range and noise) are run under the same protocol, both are written as records
of the experiment data format (``synthetic: true``, with their provenance),
and both go through the *same* analysis code
(:mod:`impact.experiment.analysis`):

* forced sweep r = 0.9 ... 1.1 (step 0.01), each point from rest for 500
  natural periods, ``sweep_curve`` (sqrt(2) RMS over whole forcing periods of
  the window 250 ... 500) -> peak amplitude x_max, its frequency (vertex of
  1/A^2 in r^2 through the three highest samples), half-power damping where
  the grid resolves it, impacts per cycle (``count_impacts`` on the relative
  displacement s) and beating (:func:`detect_beating`);
* free decays from x0 = 10 ... 25 mm, ``log_decrement`` per cycle against
  amplitude (samples clipped by the sensor's range are skipped).

Per case: relative error of x_max, error of the resonance frequency, error of
delta against amplitude (binned), impact counts and beating agreement
(:func:`run_case`); over the grid a table (:func:`run_validation`), the paper's
claims as the rig and the model see them (:func:`evaluate_claims`), the data of
Figs. 3 and 5 (:func:`fig3_data`, :func:`fig5_data`) and their plots.  The
rig's fidelity features can be switched off one at a time
(:func:`ablation`) to see which one dominates the model-rig differences.

Nothing here is the paper's data: every record says ``synthetic: true`` and
names its generator in ``source``.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable

import numpy as np
from numba import njit

from .. import _kernels as K
from ..core.jitcache import purge_stale_cache
from ..core.sampler import paper_free_flight, paper_state
from ..params import Protocol, System
from ..simulate import STICK_VELOCITY, ensure_compiled, initial_state, pid_data
from ..simulate import param_vector as model_param_vector
from . import rig as R
from .analysis import (
    UnresolvedPeakError,
    beta_to_delta,
    count_impacts,
    half_power,
    impacts_per_cycle,
    log_decrement,
    sweep_curve,
    whole_periods,
)
from .records import Record, make_record, write_record

MODEL_SOURCE = ("model: Eq. (4) of the paper (linear pendulum, instantaneous impacts) simulated by the "
                "production exact event-driven kernel impact._kernels.run; synthetic")

# ----------------------------------------------------------------------------
# configuration
# ----------------------------------------------------------------------------

VALIDATION_DEFAULTS: dict[str, Any] = {
    "grid": {
        "mu": [0.0054, 0.0129, 0.0252],
        "gap_mm": [20.0, 30.0, 40.0],
        "rp": [0.9, 1.0, 1.1],
        "walls": ["steel", "rubber_1.0mm", "rubber_0.5mm", "cork_3.0mm"],
    },
    "bare": {   # the bare structure (Fig. 3)
        # exciter set lower for the bare structure: A_max = 0.0168 / (2 * 0.00048) = 17.5 mm < 20 mm range
        "force_ratio_mm": 0.0168,
        "settle_periods": 2000,   # ~6 time constants 1/(beta omega) at beta = 0.00048
        "record_periods": 60,
        "fine_freq": {"min": 0.99, "max": 1.01, "step": 0.0005},   # resolves beta = 0.00048 (step <= beta)
        "decay_x0_mm": [10.0, 15.0, 20.0, 25.0],
        "decay_duration_s": 240.0,
    },
    "beating": {"threshold": 0.1},   # modulation depth (max - min)/(max + min) of the per-cycle amplitude
    "delta_bins": 12,                # log-spaced amplitude bins for comparing delta(A)
    "figures": {
        "fig5a": {"mu": 0.0252, "gap_mm": 20.0, "rp": 1.0, "wall": "steel"},
        "fig5b": {"mu": 0.0129, "gap_mm": 20.0, "rp": 1.0, "wall": "rubber_1.0mm",
                  "extra_r": [0.968, 0.991, 1.008]},
    },
    "smoke": {   # a quick subset: two cases, shortened protocol
        "cases": [{"mu": 0.0252, "gap_mm": 20.0, "rp": 1.0, "wall": "steel"},
                  {"mu": 0.0054, "gap_mm": 40.0, "rp": 0.9, "wall": "cork_3.0mm"}],
        "protocol": {"periods": 120, "average_from": 60, "freq": {"min": 0.9, "max": 1.1, "step": 0.025}},
        "free_decay": {"x0_mm": [15.0], "duration_s": 20.0},
        "bare": {"settle_periods": 200, "record_periods": 20,
                 "fine_freq": {"min": 0.995, "max": 1.005, "step": 0.001},
                 "decay_x0_mm": [15.0], "decay_duration_s": 40.0},
    },
    "processes": 2,
    "ablation": {
        # the grid's largest discrepancies and two typical cases (see docs/experiment-data.md)
        "cases": [{"mu": 0.0252, "gap_mm": 40.0, "rp": 1.1, "wall": "steel"},
                  {"mu": 0.0252, "gap_mm": 40.0, "rp": 0.9, "wall": "steel"},
                  {"mu": 0.0054, "gap_mm": 40.0, "rp": 1.0, "wall": "cork_3.0mm"},
                  {"mu": 0.0252, "gap_mm": 20.0, "rp": 1.1, "wall": "cork_3.0mm"},
                  {"mu": 0.0129, "gap_mm": 30.0, "rp": 1.0, "wall": "rubber_0.5mm"},
                  {"mu": 0.0252, "gap_mm": 30.0, "rp": 1.0, "wall": "steel"},
                  {"mu": 0.0054, "gap_mm": 20.0, "rp": 1.0, "wall": "steel"}],
        "variants": {
            "full": {},
            "no_nonlinear_pendulum": {"nonlinear_pendulum": False},
            "no_finite_radius": {"finite_radius": False},
            "stiff_contact": {"stiffness_scale": 1.0e4},
            "no_sensor": {"sensor": False},
            "point_mass_length_rule": {"length_rule": "point_mass"},
            "all_off": {"nonlinear_pendulum": False, "finite_radius": False, "stiffness_scale": 1.0e4,
                        "sensor": False},
        },
    },
}


def validation_config(cfg: dict | None = None, *, smoke: bool = False) -> dict[str, Any]:
    """The rig's configuration plus the validation keys, ``cfg`` laid over the defaults.

    ``smoke=True`` lays the ``smoke`` section over the result (shortened
    protocol, two cases) for tests and quick runs.
    """
    if cfg and set(cfg) == {"validation"}:  # the whole file under one top-level key
        cfg = cfg["validation"]
    base = R.merged_config(None)
    base.update(json.loads(json.dumps(VALIDATION_DEFAULTS)))
    out = _merge(base, cfg or {})
    check_config(out)
    if smoke:
        sm = out.get("smoke", {})
        out = _merge(out, {k: v for k, v in sm.items() if k != "cases"})
    return out


def check_config(cfg: dict) -> None:
    """Refuse unknown keys and inconsistent grids (ValueError naming the key)."""
    known = set(R.DEFAULT_CONFIG) | set(VALIDATION_DEFAULTS)
    unknown = sorted(set(cfg) - known)
    if unknown:
        raise ValueError(f"validation config: unknown key(s) {unknown} (allowed: {sorted(known)})")
    for section in ("structure", "balls", "pendulum", "contact", "excitation", "sensor", "fidelity",
                    "integrator", "protocol", "free_decay", "drop_test", "bare", "beating"):
        ref = {**R.DEFAULT_CONFIG, **VALIDATION_DEFAULTS}[section]
        bad = sorted(set(cfg.get(section, {})) - set(ref))
        if bad:
            raise ValueError(f"validation config: unknown key(s) {bad} in {section} (allowed: {sorted(ref)})")
    balls = cfg["balls"]
    if len(balls["mu"]) != len(balls["diameters_mm"]):
        raise ValueError("validation config: balls.mu and balls.diameters_mm differ in length")
    for mu in cfg["grid"]["mu"]:
        if not any(abs(mu - m) <= 1e-9 for m in balls["mu"]):
            raise ValueError(f"validation config: grid.mu {mu} is not one of balls.mu {balls['mu']}")
    for w in cfg["grid"]["walls"]:
        if w not in cfg["walls"]:
            raise ValueError(f"validation config: grid wall {w!r} is not defined under walls")
        e = float(cfg["walls"][w]["e"])
        if not 0.0 < e <= 1.0:
            raise ValueError(f"validation config: walls.{w}.e = {e} must be in (0, 1]")
    pr = cfg["protocol"]
    if not 0 <= pr["average_from"] < pr["periods"]:
        raise ValueError("validation config: protocol.average_from must be in [0, periods)")


def _merge(dst: dict, src: dict) -> dict:
    out = json.loads(json.dumps(dst))
    for key, val in src.items():
        if isinstance(val, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], val)
        else:
            out[key] = json.loads(json.dumps(val))
    return out


def frequency_values(freq: dict, extra: Iterable[float] = ()) -> np.ndarray:
    """The sweep grid min, min + step, ..., max (rounded), plus ``extra`` values, sorted."""
    n = int(math.floor((freq["max"] - freq["min"]) / freq["step"] + 1e-9)) + 1
    grid = np.round(freq["min"] + freq["step"] * np.arange(n), 10)
    return np.unique(np.concatenate([grid, np.round(np.asarray(list(extra), dtype=float), 10)]))


@dataclass(frozen=True)
class Case:
    """One configuration of the experimental grid."""

    mu: float
    gap_mm: float
    rp: float
    wall: str

    @property
    def id(self) -> str:
        return f"mu{self.mu:g}_d{self.gap_mm:g}_rp{self.rp:g}_{self.wall}"

    @classmethod
    def of(cls, obj) -> "Case":
        if isinstance(obj, Case):
            return obj
        if isinstance(obj, str):
            for c in all_cases(None):
                if c.id == obj:
                    return c
            raise ValueError(f"unknown case id {obj!r}")
        return cls(float(obj["mu"]), float(obj["gap_mm"]), float(obj["rp"]), str(obj["wall"]))


def all_cases(cfg: dict | None) -> list[Case]:
    """The grid mu x d x r' x wall of the configuration (108 cases by default)."""
    g = validation_config(cfg)["grid"]
    return [Case(mu, d, rp, w) for mu in g["mu"] for d in g["gap_mm"] for rp in g["rp"] for w in g["walls"]]


def wall_e(cfg: dict, wall: str) -> float:
    return float(cfg["walls"][wall]["e"])


# ----------------------------------------------------------------------------
# the model (Eq. 4, production kernel), sampled into records
# ----------------------------------------------------------------------------


def model_system(cfg: dict, case: Case) -> System:
    """Eq. (4) in model units (M = 1, omega = 1, lengths in mm) for a case."""
    return System(kind="pid", mu=case.mu, beta=float(cfg["structure"]["beta"]), e=wall_e(cfg, case.wall),
                  gap=case.gap_mm, rp=case.rp, force_ratio=float(cfg["excitation"]["force_ratio_mm"]),
                  phase=float(cfg["excitation"].get("phase", 0.0)),
                  frequency_hz=float(cfg["structure"]["frequency_hz"]), unit_m=1e-3)


@njit(cache=True)
def _model_chunk_dense(p, z, code, pid, ta, tb, ts, i0, i1, xs, ss, rec, diag, zo):
    """One call of the production kernel over [ta, tb]; samples ts[i0:i1] in (ta, tb] rebuilt from its events.

    Between impacts the kernel's motion is the closed-form free flight from
    the post-impact state (the kernel's own closed form, through the public
    sampler :mod:`impact.core.sampler`), so the samples are exact.  Returns (new code, ok): ok = False
    when the chunk contains a sticking episode (a release is not recorded) or
    more impacts than ``rec`` holds -- then the caller re-runs it sample by
    sample.
    """
    p[K.P_T0] = ta
    p[K.P_TEND] = tb
    code_new = K.run(p, z, code, pid, None, rec, diag, zo)
    nr = int(diag[K.D_NREC])
    if code % 10 != K.MODE_FREE or nr >= rec.shape[0] or diag[K.D_CAP] > 0.0:
        return code_new, False
    for j in range(nr):
        if rec[j, 7] > 0.0:
            return code_new, False
    kap = np.zeros(K.NT, dtype=np.complex128)
    cx = np.zeros(K.NT, dtype=np.complex128)
    cy = np.zeros(K.NT, dtype=np.complex128)
    poly = np.zeros(2)
    zs = z.copy()
    zt = np.zeros(4)
    t_seg = ta
    half = 0.5 * p[K.P_D]
    j = 0
    paper_free_flight(kap, cx, cy, poly, zs, t_seg, p, pid)
    for i in range(i0, i1):
        while j < nr and rec[j, 0] <= ts[i]:
            side = rec[j, 1]
            zs[0] = rec[j, 2]
            zs[1] = rec[j, 5]
            zs[2] = rec[j, 2] + side * half
            zs[3] = rec[j, 6]
            t_seg = rec[j, 0]
            paper_free_flight(kap, cx, cy, poly, zs, t_seg, p, pid)
            j += 1
        paper_state(kap, cx, cy, poly, ts[i] - t_seg, zt)
        xs[i] = zt[0]
        ss[i] = zt[2] - zt[0]
    return code_new, True


@njit(cache=True)
def _model_samples(p, z0, code0, pid, t0, ts, xs, ss, imp, out, chunk):
    """Run the production kernel from t0 through the sample times ts (model units).

    The kernel runs over chunks of ``chunk`` samples; inside a chunk the
    samples are rebuilt exactly from its impact records
    (:func:`_model_chunk_dense`), or -- if the chunk holds a sticking episode
    -- by one kernel call per sample interval.  x and s = y - x at every
    sample; impact times and walls into imp; out = (impacts, event cap
    reached, final contact code).
    """
    rec = np.zeros((512, K.NREC))
    diag = np.zeros(K.NDIAG)
    z = z0.copy()
    zo = np.zeros(4)
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
        p[K.P_T0] = t
        p[K.P_TEND] = ts[i]
        code = K.run(p, z, code, pid, None, rec, diag, zo)
        if diag[K.D_CAP] > 0.0 or diag[K.D_TEND] < ts[i]:
            cap = 1.0
        for k in range(4):
            z[k] = zo[k]
        t = ts[i]
        xs[i] = z[0]
        ss[i] = z[2] - z[0]
        i += 1
    while i < n:
        i1 = min(i + chunk, n)
        tb = ts[i1 - 1]
        code_new, ok = _model_chunk_dense(p, z, code, pid, t, tb, ts, i, i1, xs, ss, rec, diag, zo)
        if ok:
            nr = int(diag[K.D_NREC])
            for j in range(nr):
                if nimp < imp.shape[0]:
                    imp[nimp, 0] = rec[j, 0]
                    imp[nimp, 1] = rec[j, 1]
                nimp += 1
            code = code_new
            for k in range(4):
                z[k] = zo[k]
            t = tb
        else:
            # sample by sample from the chunk's start
            for ii in range(i, i1):
                if ts[ii] > t:
                    p[K.P_T0] = t
                    p[K.P_TEND] = ts[ii]
                    code = K.run(p, z, code, pid, None, rec, diag, zo)
                    nr = int(diag[K.D_NREC])
                    for j in range(nr):
                        if nimp < imp.shape[0]:
                            imp[nimp, 0] = rec[j, 0]
                            imp[nimp, 1] = rec[j, 1]
                        nimp += 1
                    if diag[K.D_CAP] > 0.0 or diag[K.D_TEND] < ts[ii]:
                        cap = 1.0
                    for k in range(4):
                        z[k] = zo[k]
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
    system = model_system(cfg, case)
    ensure_compiled("pid")
    omega = 2.0 * math.pi * float(cfg["structure"]["frequency_hz"])
    prot = Protocol(periods=1.0, average_from=0.0)
    p = model_param_vector(system, r, prot)
    p[K.P_TWIN] = 0.0
    data = pid_data(system, r)
    if forced:
        z0, code = initial_state(system, "centre")
    else:
        lam, vec, vinv, zc = data
        data = (lam, vec, vinv, np.zeros_like(zc))
        p[K.P_F] = 0.0
        p[K.P_VSTICK] = STICK_VELOCITY * max(abs(x0_mm), 1e-6)
        z0 = np.array([x0_mm, 0.0, x0_mm, 0.0])
        code = K.encode_contact(K.MODE_FREE, 0, 0)
    tm = np.ascontiguousarray(ts_s * omega)
    xs = np.empty(tm.size)
    ss = np.empty(tm.size)
    imp = np.zeros((200000, 2))
    out = np.zeros(3)
    # settle: one kernel call up to the first sample, then chunks of about one forcing period
    if chunk is None:
        per_cycle = float(cfg["sensor"]["sample_rate_hz"]) / (r * float(cfg["structure"]["frequency_hz"]))
        chunk = max(1, int(round(per_cycle)))
    _model_samples(p, np.asarray(z0, dtype=float), int(code), data, 0.0, tm, xs, ss, imp, out, chunk)
    n = int(min(out[0], imp.shape[0]))
    return ModelRun(ts_s, xs, ss, imp[:n, 0] / omega, bool(out[1]))


def _model_header(cfg: dict, case: Case | None, kind: str, notes: str) -> dict:
    fs = float(cfg["sensor"]["sample_rate_hz"])
    hdr: dict[str, Any] = {"format_version": 1, "kind": kind, "synthetic": True, "sample_rate_hz": fs,
                           "units": "mm", "damper": "none" if case is None else "pid",
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


def model_forced_point(cfg: dict, case: Case, r: float) -> tuple[Record, ModelRun]:
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
    return make_record(hdr, {"t_s": ts, "x": run.x_mm, "s": run.s_mm}), run


def model_free_decay(cfg: dict, case: Case, x0_mm: float, duration_s: float) -> tuple[Record, ModelRun]:
    """The model's ``free_decay`` record: released from x0 with the pendulum hanging at rest."""
    fs = float(cfg["sensor"]["sample_rate_hz"])
    ts = np.arange(int(math.floor(duration_s * fs)) + 1) / fs
    run = _run_model(cfg, case, 1.0, ts, forced=False, x0_mm=x0_mm)
    if run.capped:
        raise RuntimeError(f"model free decay hit the event cap at {case.id} x0={x0_mm}")
    hdr = _model_header(cfg, case, "free_decay", "released from rest, pendulum hanging")
    hdr["x0_mm"] = float(x0_mm)
    return make_record(hdr, {"t_s": ts, "x": run.x_mm, "s": run.s_mm}), run


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


def model_bare_forced_point(cfg: dict, r: float, settle_periods: float, record_periods: float) -> Record:
    """Bare structure, exact closed form, sampled over the recording window."""
    ts = _window_times(cfg, settle_periods + record_periods, settle_periods)
    hdr = _model_header(cfg, None, "forced_sweep_point",
                        f"bare structure, exact SDOF from rest, window {settle_periods:g} ... "
                        f"{settle_periods + record_periods:g} periods")
    hdr["source"] = "model: Eq. (4) with mu = 0 (linear SDOF), exact closed form; synthetic"
    hdr["r"] = float(r)
    hdr["forcing_hz"] = float(r) * float(cfg["structure"]["frequency_hz"])
    return make_record(hdr, {"t_s": ts, "x": sdof_response(ts, cfg, r)})


def model_bare_free_decay(cfg: dict, x0_mm: float, duration_s: float) -> Record:
    fs = float(cfg["sensor"]["sample_rate_hz"])
    ts = np.arange(int(math.floor(duration_s * fs)) + 1) / fs
    hdr = _model_header(cfg, None, "free_decay", "bare structure, exact SDOF free decay")
    hdr["source"] = "model: Eq. (4) with mu = 0 (linear SDOF), exact closed form; synthetic"
    hdr["x0_mm"] = float(x0_mm)
    return make_record(hdr, {"t_s": ts, "x": sdof_response(ts, cfg, None, x0_mm)})


# ----------------------------------------------------------------------------
# the rig, with the validation's protocol
# ----------------------------------------------------------------------------


def rig_forced_point(cfg: dict, case: Case | None, r: float, *, fidelity: dict | None = None,
                     settle_periods: float | None = None, record_periods: float | None = None) -> R.RigOutput:
    fid = fidelity or {}
    if case is None:
        spec = R.rig_spec(cfg, bare=True, **fid)
        cid = "bare"
    else:
        spec = R.rig_spec(cfg, mu=case.mu, gap_mm=case.gap_mm, rp=case.rp, wall=case.wall, **fid)
        cid = case.id
    prot = cfg["protocol"]
    if settle_periods is None:
        periods, avg = prot["periods"], prot["average_from"]
    else:
        periods, avg = settle_periods + record_periods, settle_periods
    seed = R.seed_for(cid, "forced", round(float(r), 10), base=cfg.get("seed", 0))
    return R.forced_point(spec, r, periods=periods, average_from=avg, seed=seed,
                          wall_name=None if case is None else case.wall)


def rig_free_decay(cfg: dict, case: Case | None, x0_mm: float, duration_s: float, *,
                   fidelity: dict | None = None) -> R.RigOutput:
    fid = fidelity or {}
    if case is None:
        spec = R.rig_spec(cfg, bare=True, **fid)
        cid = "bare"
    else:
        spec = R.rig_spec(cfg, mu=case.mu, gap_mm=case.gap_mm, rp=case.rp, wall=case.wall, **fid)
        cid = case.id
    seed = R.seed_for(cid, "decay", float(x0_mm), base=cfg.get("seed", 0))
    return R.free_decay(spec, x0_mm, duration_s=duration_s, seed=seed,
                        wall_name=None if case is None else case.wall)


# ----------------------------------------------------------------------------
# analysis helpers shared by model and rig
# ----------------------------------------------------------------------------


def cycle_amplitudes(t: np.ndarray, x: np.ndarray, forcing_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Amplitude of each whole forcing cycle of a record: least-squares a cos + b sin + c per cycle.

    Returns (cycle centre times, sqrt(a^2 + b^2)); the per-cycle normal
    equations are built from cumulative sums and solved in one batch.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    T = 1.0 / forcing_hz
    dt = float(np.median(np.diff(t)))
    n = int(math.floor((t[-1] - t[0] + dt) / T + 1e-9))
    if n < 1:
        return np.array([]), np.array([])
    lo = t[0] + np.arange(n) * T - 0.5 * dt
    i0 = np.searchsorted(t, lo, side="left")
    i1 = np.searchsorted(t, lo + T, side="left")
    keep = (i1 - i0) >= 4
    i0, i1 = i0[keep], i1[keep]
    w = 2.0 * math.pi * forcing_hz
    tt = t - t[0]
    c, sn = np.cos(w * tt), np.sin(w * tt)
    xm = x - np.mean(x)

    def sums(arr):
        cs = np.concatenate([[0.0], np.cumsum(arr)])
        return cs[i1] - cs[i0]

    scc, sss, scs, sc, ss_ = sums(c * c), sums(sn * sn), sums(c * sn), sums(c), sums(sn)
    cnt = (i1 - i0).astype(float)
    a = np.empty((i0.size, 3, 3))
    a[:, 0, 0], a[:, 0, 1], a[:, 0, 2] = scc, scs, sc
    a[:, 1, 0], a[:, 1, 1], a[:, 1, 2] = scs, sss, ss_
    a[:, 2, 0], a[:, 2, 1], a[:, 2, 2] = sc, ss_, cnt
    b = np.stack([sums(xm * c), sums(xm * sn), sums(xm)], axis=1)
    coef = np.linalg.solve(a, b[:, :, None])[:, :, 0]
    tc = 0.5 * (t[i0] + t[i1 - 1])
    return tc, np.hypot(coef[:, 0], coef[:, 1])


@dataclass(frozen=True)
class Beating:
    """Amplitude modulation of a forced record over its window.

    ``modulation`` = (max - min)/(max + min) of the per-forcing-cycle
    amplitude; ``crossings`` the number of times the envelope crosses its
    mean; ``beating`` when the modulation exceeds the threshold, the
    envelope oscillates (>= 2 crossings: at least one beat, not a monotone
    transient) and its range is well above the noise of the per-cycle fit;
    ``beat_period_s`` ~ 2 window / crossings.
    """

    modulation: float
    crossings: int
    beating: bool
    beat_period_s: float


def detect_beating(t, x, forcing_hz: float, *, threshold: float = 0.1, noise_rms: float = 0.0) -> Beating:
    """Beating (a slowly modulated amplitude) in a forced record; see :class:`Beating`."""
    tc, env = cycle_amplitudes(t, x, forcing_hz)
    if env.size < 4 or not np.all(np.isfinite(env)) or env.max() <= 0:
        return Beating(math.nan, 0, False, math.nan)
    mod = float((env.max() - env.min()) / (env.max() + env.min()))
    dev = env - env.mean()
    sgn = np.sign(dev[dev != 0])
    crossings = int(np.count_nonzero(sgn[1:] != sgn[:-1]))
    fs = 1.0 / float(np.median(np.diff(t)))
    se = noise_rms * math.sqrt(2.0 * forcing_hz / fs)  # standard error of one cycle's amplitude
    beating = bool(mod > threshold and crossings >= 2 and (env.max() - env.min()) > 8.0 * se)
    span = tc[-1] - tc[0] if tc.size > 1 else math.nan
    return Beating(mod, crossings, beating, 2.0 * span / crossings if crossings else math.nan)


def peak_of_curve(r, amp) -> tuple[float, float, float]:
    """(x_max, r at x_max, refined r_peak) of a sweep curve.

    x_max is the largest sample (the paper's definition); r_peak the vertex of
    the quadratic in u = r^2 through 1/A^2 of the three highest samples when
    it lies between them (the analysis' local peak model), else the sample.
    """
    r = np.asarray(r, dtype=float)
    amp = np.asarray(amp, dtype=float)
    k = int(np.nanargmax(amp))
    xm, rk = float(amp[k]), float(r[k])
    if 0 < k < r.size - 1:
        u = r[k - 1 : k + 2] ** 2
        q = 1.0 / amp[k - 1 : k + 2] ** 2
        c = np.polyfit(u - u[1], q, 2)
        if c[0] > 0:
            u0 = -c[1] / (2 * c[0]) + u[1]
            if u[0] <= u0 <= u[2]:
                return xm, rk, float(math.sqrt(u0))
    return xm, rk, rk


def _clip_end_time(rec: Record, range_mm: float | None) -> float | None:
    """Time from which a record is free of sensor saturation (one period after the last clipped sample)."""
    if range_mm is None:
        return None
    x = rec.x_in("mm")
    clipped = np.flatnonzero(np.abs(x) >= range_mm * (1.0 - 1e-9))
    if clipped.size == 0:
        return None
    T = 1.0 / float(rec.header.get("structure_hz", 1.5))
    return float(rec.t[clipped[-1]] + T)


def decay_points(rec: Record, *, t_start: float | None = None, min_amplitude: float | None = None) -> dict:
    """delta per cycle against amplitude (mm) of a free-decay record; empty arrays if it has too few cycles."""
    try:
        ld = log_decrement(rec.t, rec.x_in("mm"), t_start=t_start, min_amplitude=min_amplitude)
    except ValueError:
        return {"amplitude": np.array([]), "delta": np.array([]), "mean": math.nan}
    return {"amplitude": ld.amplitude, "delta": ld.delta, "mean": ld.mean}


def _bin_delta(amp: np.ndarray, delta: np.ndarray, edges: np.ndarray) -> np.ndarray:
    out = np.full(edges.size - 1, np.nan)
    idx = np.digitize(amp, edges) - 1
    for b in range(out.size):
        sel = idx == b
        if np.any(sel):
            out[b] = float(np.mean(delta[sel]))
    return out


def compare_delta(model_pts: list[dict], rig_pts: list[dict], *, n_bins: int = 12,
                  min_amplitude: float = 2.0) -> dict:
    """Compare delta(A) of model and rig decays: both pooled, averaged on log-spaced amplitude bins.

    Returns the bins (centres), both binned curves and the rms and largest
    absolute difference over the bins both populate, plus the rms relative to
    the model's mean delta over those bins.
    """
    am = np.concatenate([p["amplitude"] for p in model_pts] or [np.array([])])
    dm = np.concatenate([p["delta"] for p in model_pts] or [np.array([])])
    ar = np.concatenate([p["amplitude"] for p in rig_pts] or [np.array([])])
    dr = np.concatenate([p["delta"] for p in rig_pts] or [np.array([])])
    empty = {"centres": np.array([]), "model": np.array([]), "rig": np.array([]), "rms": math.nan,
             "max": math.nan, "rel": math.nan, "bins_compared": 0}
    if am.size == 0 or ar.size == 0:
        return empty
    hi = max(am.max(), ar.max())
    lo = max(min_amplitude, min(am.min(), ar.min()))
    if not hi > lo:
        return empty
    # at least ~4 cycles per bin and source
    n_bins = max(1, min(n_bins, min(am.size, ar.size) // 4))
    edges = np.geomspace(lo, hi * (1 + 1e-9), n_bins + 1)
    bm, br = _bin_delta(am, dm, edges), _bin_delta(ar, dr, edges)
    both = np.isfinite(bm) & np.isfinite(br)
    centres = np.sqrt(edges[:-1] * edges[1:])
    if not np.any(both):
        return {**empty, "centres": centres, "model": bm, "rig": br}
    diff = br[both] - bm[both]
    rms = float(np.sqrt(np.mean(diff**2)))
    scale = float(np.mean(np.abs(bm[both])))
    return {"centres": centres, "model": bm, "rig": br, "rms": rms, "max": float(np.max(np.abs(diff))),
            "rel": rms / scale if scale > 0 else math.nan, "bins_compared": int(np.count_nonzero(both))}


def _aipc(rec: Record, d_mm: float, forcing_hz: float) -> float:
    t = rec.t
    ic = count_impacts(t, s=rec.s_in("mm"), d=d_mm)
    dt = float(np.median(np.diff(t)))
    lo, hi = whole_periods(float(t[0]), float(t[-1]) + dt, 1.0 / forcing_hz)
    return impacts_per_cycle(ic.times, forcing_hz, lo, hi)


def _half_power(r, amp) -> tuple[float, bool, str]:
    try:
        hp = half_power(r, amp)
        return hp.beta, True, ""
    except UnresolvedPeakError as exc:
        return math.nan, False, str(exc).split(";")[0]
    except ValueError as exc:
        return math.nan, False, str(exc)


# ----------------------------------------------------------------------------
# one case
# ----------------------------------------------------------------------------


@dataclass
class CaseResult:
    """Per-case summary row, per-r curve rows, per-bin delta rows (and optionally the records)."""

    row: dict
    curve: list[dict]
    delta: list[dict]
    records: dict = field(default_factory=dict)


def sweep_pair(cfg: dict, case: Case, r_values, *, fidelity: dict | None = None, keep: bool = False) -> dict:
    """Model and rig records over a frequency sweep, and their analysis (same code for both)."""
    fhz = float(cfg["structure"]["frequency_hz"])
    thr = float(cfg["beating"]["threshold"])
    recs = {"model": [], "rig": []}
    rows = []
    rig_pen = 0.0
    t_model = t_rig = 0.0
    for r in r_values:
        t0 = time.perf_counter()
        mrec, mrun = model_forced_point(cfg, case, float(r))
        t1 = time.perf_counter()
        rout = rig_forced_point(cfg, case, float(r), fidelity=fidelity)
        t2 = time.perf_counter()
        fz = float(r) * fhz
        lo, hi = whole_periods(float(mrec.t[0]), float(mrec.t[-1]) + float(np.median(np.diff(mrec.t))), 1.0 / fz)
        ep = rout.raw.episodes
        true_aipc = {"model": impacts_per_cycle(mrun.impact_times_s, fz, lo, hi),
                     # contact episodes entered faster than the HC floor speed count as impacts
                     "rig": impacts_per_cycle(ep[ep[:, 2] > float(cfg["contact"]["v_floor_m_s"]), 0], fz, lo, hi)}
        t_model += t1 - t0
        t_rig += t2 - t1
        rig_pen = max(rig_pen, rout.raw.max_penetration)
        recs["model"].append(mrec)
        recs["rig"].append(rout.record)
        row = {"r": float(r)}
        for who, rec in (("model", mrec), ("rig", rout.record)):
            b = detect_beating(rec.t, rec.x_in("mm"), float(r) * fhz, threshold=thr,
                               noise_rms=float(rec.header.get("noise_rms", 0.0)))
            row[f"{who}_aipc"] = _aipc(rec, case.gap_mm, float(r) * fhz)
            row[f"{who}_aipc_true"] = true_aipc[who]
            row[f"{who}_modulation"] = b.modulation
            row[f"{who}_beating"] = b.beating
            row[f"{who}_beat_period_s"] = b.beat_period_s
        rows.append(row)
    curves = {who: sweep_curve(recs[who]) for who in ("model", "rig")}
    for row, am, ar in zip(rows, curves["model"].amplitude, curves["rig"].amplitude):
        row["model_amp_mm"] = float(am)
        row["rig_amp_mm"] = float(ar)
    out = {"rows": rows, "curves": curves, "rig_max_penetration_m": rig_pen, "time_model_s": t_model,
           "time_rig_s": t_rig}
    if keep:
        out["records"] = recs
    return out


def decay_pair(cfg: dict, case: Case | None, x0s, duration_s: float, *, fidelity: dict | None = None,
               keep: bool = False) -> dict:
    """Model and rig free decays from each x0 and their delta(A) (clipped samples skipped in both)."""
    min_amp = float(cfg["free_decay"].get("min_amplitude_mm", 2.0))
    rng_mm = float(cfg["sensor"]["range_mm"])
    pts = {"model": [], "rig": []}
    recs = {"model": [], "rig": []}
    for x0 in x0s:
        if case is None:
            mrec = model_bare_free_decay(cfg, x0, duration_s)
        else:
            mrec, _ = model_free_decay(cfg, case, x0, duration_s)
        rrec = rig_free_decay(cfg, case, x0, duration_s, fidelity=fidelity).record
        t_start = _clip_end_time(rrec, rng_mm)
        for who, rec in (("model", mrec), ("rig", rrec)):
            p = decay_points(rec, t_start=t_start, min_amplitude=min_amp)
            p["x0_mm"] = float(x0)
            pts[who].append(p)
            recs[who].append(rec)
    out = {"points": pts}
    if keep:
        out["records"] = recs
    return out


def run_case(cfg: dict, case: Case, *, fidelity: dict | None = None, keep_records: bool = False,
             r_values=None) -> CaseResult:
    """Model vs rig for one case: sweep, free decays, errors (see the module docstring)."""
    cfg = validation_config(cfg) if "grid" not in cfg else cfg
    warm_up()
    t0 = time.perf_counter()
    rv = frequency_values(cfg["protocol"]["freq"]) if r_values is None else np.asarray(r_values, dtype=float)
    sw = sweep_pair(cfg, case, rv, fidelity=fidelity, keep=keep_records)
    fd = cfg["free_decay"]
    dc = decay_pair(cfg, case, fd["x0_mm"], float(fd["duration_s"]), fidelity=fidelity, keep=keep_records)
    amax = float(cfg["excitation"]["force_ratio_mm"]) / (2.0 * float(cfg["structure"]["beta"]))
    row: dict[str, Any] = {"case": case.id, "mu": case.mu, "gap_mm": case.gap_mm, "rp": case.rp,
                           "wall": case.wall, "e": wall_e(cfg, case.wall),
                           "ball_diameter_mm": R.diameter_for_mu(cfg, case.mu), "gap_ratio": case.gap_mm / amax}
    for who in ("model", "rig"):
        c = sw["curves"][who]
        xm, rk, rpk = peak_of_curve(c.r, c.amplitude)
        beta_hp, resolved, _why = _half_power(c.r, c.amplitude)
        row.update({f"{who}_xmax_mm": xm, f"{who}_Xm": xm / amax, f"{who}_r_at_max": rk, f"{who}_r_peak": rpk,
                    f"{who}_beta_hp": beta_hp, f"{who}_hp_resolved": resolved})
        kk = int(np.argmax(c.amplitude))
        row[f"{who}_aipc_at_max"] = sw["rows"][kk][f"{who}_aipc"]
        row[f"{who}_aipc_true_at_max"] = sw["rows"][kk][f"{who}_aipc_true"]
        row[f"{who}_n_beating"] = int(sum(bool(rw[f"{who}_beating"]) for rw in sw["rows"]))
        row[f"{who}_delta_mean"] = float(np.nanmean([p["mean"] for p in dc["points"][who]] or [math.nan]))
    am = np.array([rw["model_amp_mm"] for rw in sw["rows"]])
    ar = np.array([rw["rig_amp_mm"] for rw in sw["rows"]])
    row["err_xmax_rel"] = (row["rig_xmax_mm"] - row["model_xmax_mm"]) / row["model_xmax_mm"]
    row["err_r_peak"] = row["rig_r_peak"] - row["model_r_peak"]
    row["err_r_at_max"] = row["rig_r_at_max"] - row["model_r_at_max"]
    row["err_curve_rms_rel"] = float(np.sqrt(np.mean(((ar - am) / am) ** 2)))
    row["err_curve_max_rel"] = float(np.max(np.abs(ar - am) / am))
    row["err_aipc_mean_abs"] = float(np.mean([abs(rw["rig_aipc"] - rw["model_aipc"]) for rw in sw["rows"]]))
    row["beating_agreement"] = float(np.mean([rw["rig_beating"] == rw["model_beating"] for rw in sw["rows"]]))
    cd = compare_delta(dc["points"]["model"], dc["points"]["rig"], n_bins=int(cfg.get("delta_bins", 12)),
                       min_amplitude=float(cfg["free_decay"].get("min_amplitude_mm", 2.0)))
    row["err_delta_rms"] = cd["rms"]
    row["err_delta_max"] = cd["max"]
    row["err_delta_rel"] = cd["rel"]
    row["delta_bins_compared"] = cd["bins_compared"]
    row["rig_max_penetration_mm"] = sw["rig_max_penetration_m"] * 1e3
    row["time_model_s"] = sw["time_model_s"]
    row["time_rig_s"] = sw["time_rig_s"]
    row["time_case_s"] = time.perf_counter() - t0
    curve = [{"case": case.id, **rw} for rw in sw["rows"]]
    delta = [{"case": case.id, "amplitude_mm": float(c), "model_delta": float(m), "rig_delta": float(g)}
             for c, m, g in zip(cd["centres"], cd["model"], cd["rig"])]
    recs = {}
    if keep_records:
        recs = {"sweep": sw["records"], "decay": dc["records"], "decay_points": dc["points"]}
    return CaseResult(row, curve, delta, recs)


def _run_case_worker(args):
    cfg, case, fidelity = args
    return run_case(cfg, case, fidelity=fidelity)


def _map(fn, items, processes: int):
    items = list(items)
    if processes <= 1 or len(items) <= 1:
        return [fn(it) for it in items]
    import multiprocessing as mp

    warm_up()
    ctx = mp.get_context("fork")
    with ctx.Pool(processes) as pool:
        return pool.map(fn, items, chunksize=1)


_WARM = False


def _warm_model_sampler():
    """Compile (or load) the model sampler, under the simulator's JIT lock."""
    global _WARM
    if _WARM:
        return
    import fcntl

    from ..simulate import _cache_dir

    ensure_compiled("pid")
    folder = _cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "impact-jit.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            cfg = validation_config(None)
            _run_model(cfg, Case(0.0129, 30.0, 1.0, "steel"), 1.0, np.array([0.0, 0.01]), forced=True)
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)
    _WARM = True


def warm_up() -> None:
    """Compile (or load from cache) every kernel the validation uses."""
    R.warm_up()
    _warm_model_sampler()


# ----------------------------------------------------------------------------
# bare structure (Fig. 3) and the Fig. 5 cases
# ----------------------------------------------------------------------------


def fig3_data(cfg: dict | None = None, *, keep_records: bool = False) -> dict:
    """Fig. 3: the bare structure, rig ("experiment") and model.

    (a) free decays from x0 (``bare.decay_x0_mm``): delta per cycle against
    amplitude, both; the model's exact delta = 2 pi beta / sqrt(1 - beta^2).
    (b) forced sweep on the paper's grid (``protocol.freq``) and on a fine grid
    around the resonance (``bare.fine_freq``), each point settled for
    ``bare.settle_periods``; half-power beta on each grid where resolvable.
    """
    cfg = validation_config(cfg) if "grid" not in (cfg or {}) else cfg
    b = cfg["bare"]
    cfg = _merge(cfg, {"excitation": {"force_ratio_mm": float(b.get("force_ratio_mm",
                                                                    cfg["excitation"]["force_ratio_mm"]))}})
    dc = decay_pair(cfg, None, b["decay_x0_mm"], float(b["decay_duration_s"]), keep=keep_records)
    decay_rows = []
    for who in ("model", "rig"):
        for p in dc["points"][who]:
            for a, d in zip(p["amplitude"], p["delta"]):
                decay_rows.append({"source": who, "x0_mm": p["x0_mm"], "amplitude_mm": float(a), "delta": float(d)})
    import pandas as pd

    decay = pd.DataFrame(decay_rows, columns=["source", "x0_mm", "amplitude_mm", "delta"])
    means = {who: float(np.mean(decay.loc[decay.source == who, "delta"])) if (decay.source == who).any()
             else math.nan for who in ("model", "rig")}
    sweeps = {}
    recs = {}
    for grid_name, freq in (("paper_grid", cfg["protocol"]["freq"]), ("fine_grid", b["fine_freq"])):
        rv = frequency_values(freq)
        mrecs = [model_bare_forced_point(cfg, float(r), b["settle_periods"], b["record_periods"]) for r in rv]
        rrecs = [rig_forced_point(cfg, None, float(r), settle_periods=b["settle_periods"],
                                  record_periods=b["record_periods"]).record for r in rv]
        cm, cr = sweep_curve(mrecs), sweep_curve(rrecs)
        hp = {}
        for who, c in (("model", cm), ("rig", cr)):
            beta_hp, ok, why = _half_power(c.r, c.amplitude)
            hp[who] = {"beta": beta_hp, "resolved": ok, "why": why}
        sweeps[grid_name] = {"r": cm.r, "model_amp_mm": cm.amplitude, "rig_amp_mm": cr.amplitude,
                             "half_power": hp, "step": float(freq["step"])}
        if keep_records:
            recs[grid_name] = {"model": mrecs, "rig": rrecs}
    beta = float(cfg["structure"]["beta"])
    rr = np.linspace(float(cfg["protocol"]["freq"]["min"]), float(cfg["protocol"]["freq"]["max"]), 4001)
    fr = float(cfg["excitation"]["force_ratio_mm"])
    out = {"decay": decay, "delta_mean": means, "delta_exact": beta_to_delta(beta), "sweeps": sweeps,
           "steady_curve": {"r": rr, "amp_mm": fr / np.sqrt((1 - rr**2) ** 2 + (2 * beta * rr) ** 2)},
           "beta": beta}
    if keep_records:
        out["records"] = {"decay": dc.get("records"), "sweep": recs}
    return out


def fig5_data(cfg: dict | None = None, *, keep_records: bool = False) -> dict:
    """Fig. 5: (a) free-decay delta - delta_bare against amplitude, PID with steel walls vs bare;
    (b) forced sweep with 1.0 mm rubber (e = 0.46), with the extra points r = 0.968, 0.991, 1.008
    and beating flags / time histories there.

    The paper does not give mu, d or r' of these panels: they are configuration
    (``figures.fig5a``, ``figures.fig5b``).
    """
    import pandas as pd

    cfg = validation_config(cfg) if "grid" not in (cfg or {}) else cfg
    fa = cfg["figures"]["fig5a"]
    ca = Case.of(fa)
    fd = cfg["free_decay"]
    x0s = fd["x0_mm"]
    dur = float(fd["duration_s"])
    pid = decay_pair(cfg, ca, x0s, dur, keep=keep_records)
    bare = decay_pair(cfg, None, x0s, dur, keep=keep_records)
    bare_mean = {who: float(np.nanmean([p["mean"] for p in bare["points"][who]])) for who in ("model", "rig")}
    rows = []
    for who in ("model", "rig"):
        for system, dd in (("pid", pid), ("bare", bare)):
            for p in dd["points"][who]:
                for a, d in zip(p["amplitude"], p["delta"]):
                    rows.append({"source": who, "system": system, "x0_mm": p["x0_mm"], "amplitude_mm": float(a),
                                 "delta": float(d), "delta_minus_bare": float(d) - bare_mean[who]})
    a_df = pd.DataFrame(rows, columns=["source", "system", "x0_mm", "amplitude_mm", "delta", "delta_minus_bare"])
    fb = cfg["figures"]["fig5b"]
    cb = Case.of(fb)
    rv = frequency_values(cfg["protocol"]["freq"], fb.get("extra_r", ()))
    sw = sweep_pair(cfg, cb, rv, keep=True)
    b_df = pd.DataFrame(sw["rows"])
    hist = {}
    for r_show in fb.get("extra_r", ()):
        k = int(np.argmin(np.abs(rv - r_show)))
        hist[float(r_show)] = {who: {"t": sw["records"][who][k].t, "x": sw["records"][who][k].x_in("mm")}
                               for who in ("model", "rig")}
    out = {"a": {"case": ca.id, "data": a_df, "bare_delta_mean": bare_mean},
           "b": {"case": cb.id, "data": b_df, "histories": hist}}
    if keep_records:
        out["records"] = {"fig5a_pid": pid.get("records"), "fig5a_bare": bare.get("records"),
                          "fig5b": sw["records"]}
    return out


# ----------------------------------------------------------------------------
# claims
# ----------------------------------------------------------------------------


def _local_peaks(amp: np.ndarray) -> np.ndarray:
    """Indices of interior local maxima of a sampled curve."""
    a = np.asarray(amp)
    return np.flatnonzero((a[1:-1] > a[:-2]) & (a[1:-1] >= a[2:])) + 1


def evaluate_claims(cfg: dict, table, curves, fig3: dict | None = None, fig5: dict | None = None) -> dict:
    """Which of the paper's Sect. 3 claims the rig and the model support, with the numbers."""
    claims: dict[str, Any] = {}
    beta = float(cfg["structure"]["beta"])
    if fig3 is not None:
        hp = {g: {who: v["half_power"][who] for who in ("model", "rig")} for g, v in fig3["sweeps"].items()}
        rig_fine = hp["fine_grid"]["rig"]
        claims["beta_half_power"] = {
            "paper": "beta = 0.00048 from the half-power method (Fig. 3b)",
            "paper_grid_step": fig3["sweeps"]["paper_grid"]["step"],
            "fine_grid_step": fig3["sweeps"]["fine_grid"]["step"],
            "half_power": hp,
            "rig_supported_on_paper_grid": bool(hp["paper_grid"]["rig"]["resolved"]
                                                and abs(hp["paper_grid"]["rig"]["beta"] / beta - 1) < 0.05),
            "rig_supported_on_fine_grid": bool(rig_fine["resolved"] and abs(rig_fine["beta"] / beta - 1) < 0.05),
            "note": "the 0.01 grid is ~10 half-power bandwidths wide; only a grid with step <= ~beta resolves it",
        }
        dm = fig3["delta_mean"]
        claims["delta_bare"] = {
            "paper": "average delta = 0.003 for the bare structure (Fig. 3a)",
            "exact": fig3["delta_exact"], "rig_mean": dm["rig"], "model_mean": dm["model"],
            "rig_supported": bool(abs(dm["rig"] / 0.003 - 1) < 0.1),
            "model_supported": bool(abs(dm["model"] / 0.003 - 1) < 0.1),
        }
    if table is not None and len(table):
        t = table
        walls = list(cfg["grid"]["walls"])
        es = [wall_e(cfg, w) for w in walls]
        order = [w for _, w in sorted(zip(es, walls))]
        res = {}
        for who in ("model", "rig"):
            full, pairs, groups = 0, 0, 0
            mean_xm = {w: float(t.loc[t.wall == w, f"{who}_Xm"].mean()) for w in order}
            for _, g in t.groupby(["mu", "gap_mm", "rp"]):
                if set(g.wall) != set(order):
                    continue
                xm = [float(g.loc[g.wall == w, f"{who}_Xm"].iloc[0]) for w in order]
                groups += 1
                ok = [xm[i] < xm[i + 1] for i in range(len(xm) - 1)]
                full += all(ok)
                pairs += sum(ok)
            res[who] = {"groups": groups, "fully_ordered": full,
                        "fraction_fully_ordered": full / groups if groups else math.nan,
                        "fraction_adjacent_pairs_ordered": pairs / (groups * (len(order) - 1)) if groups else math.nan,
                        "mean_Xm_by_e": {f"{wall_e(cfg, w):g}": mean_xm[w] for w in order},
                        "mean_Xm_increasing_with_e": bool(all(mean_xm[order[i]] < mean_xm[order[i + 1]]
                                                              for i in range(len(order) - 1)))}
        claims["e_ordering"] = {"paper": "efficiency e = 0.37 > 0.46 > 0.58 > 0.64 (X_m increasing with e)",
                                **res}
    if curves is not None and len(curves):
        res = {}
        cv = curves
        for who in ("model", "rig"):
            at_peak, peak_beat, off_peak, off_beat = 0, 0, 0, 0
            for _, g in cv.groupby("case"):
                g = g.sort_values("r")
                amp = g[f"{who}_amp_mm"].to_numpy()
                beat = g[f"{who}_beating"].to_numpy().astype(bool)
                pk = set(_local_peaks(amp).tolist())
                for i in range(amp.size):
                    if i in pk:
                        at_peak += 1
                        peak_beat += beat[i]
                    else:
                        off_peak += 1
                        off_beat += beat[i]
            res[who] = {"local_peaks": at_peak, "beating_at_peaks": int(peak_beat),
                        "fraction_beating_at_peaks": peak_beat / at_peak if at_peak else math.nan,
                        "points_off_peaks": off_peak, "beating_off_peaks": int(off_beat),
                        "fraction_beating_off_peaks": off_beat / off_peak if off_peak else math.nan}
            res[who]["supported"] = bool(res[who]["fraction_beating_off_peaks"]
                                         > res[who]["fraction_beating_at_peaks"])
        claims["beating_away_from_peaks"] = {
            "paper": "steady (equal peaks) at and near local peaks, beating away from them (Fig. 4)", **res}
    if fig5 is not None:
        b = fig5["b"]["data"]
        pts = {}
        for r_show in cfg["figures"]["fig5b"].get("extra_r", ()):
            k = int(np.argmin(np.abs(b["r"].to_numpy() - r_show)))
            pts[f"{r_show:g}"] = {who: {"beating": bool(b[f"{who}_beating"].iloc[k]),
                                        "modulation": float(b[f"{who}_modulation"].iloc[k]),
                                        "beat_period_s": float(b[f"{who}_beat_period_s"].iloc[k]),
                                        "amp_mm": float(b[f"{who}_amp_mm"].iloc[k])} for who in ("model", "rig")}
        peaks = {who: [float(b["r"].iloc[i]) for i in _local_peaks(b[f"{who}_amp_mm"].to_numpy())]
                 for who in ("model", "rig")}
        claims["fig5b"] = {"paper": "local peak near r = 0.968 without beating; beating at r = 0.991, 1.008, "
                                    "the beat period shorter beyond r = 1",
                           "case": fig5["b"]["case"], "points": pts, "local_peaks": peaks}
    if table is not None and len(table):
        t = table
        claims["agreement"] = {
            "paper": "all simulations of the grid agree well with the experiment",
            "cases": int(len(t)),
            "err_xmax_rel_median_abs": float(np.nanmedian(np.abs(t.err_xmax_rel))),
            "err_xmax_rel_worst": float(t.err_xmax_rel.iloc[int(np.nanargmax(np.abs(t.err_xmax_rel)))]),
            "err_r_peak_median_abs": float(np.nanmedian(np.abs(t.err_r_peak))),
            "err_r_peak_worst": float(t.err_r_peak.iloc[int(np.nanargmax(np.abs(t.err_r_peak)))]),
            "err_delta_rms_median": float(np.nanmedian(t.err_delta_rms)),
            "err_delta_rms_worst": float(np.nanmax(t.err_delta_rms)),
        }
    return _jsonable(claims)


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return [_jsonable(v) for v in obj.tolist()]
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if math.isfinite(v) else None
    return obj


# ----------------------------------------------------------------------------
# ablation: which fidelity feature makes the difference
# ----------------------------------------------------------------------------


def ablation(cfg: dict | None = None, cases=None, variants: dict | None = None, processes: int = 1):
    """Model-vs-rig errors with the rig's fidelity features switched off one at a time.

    Returns a DataFrame: one row per (case, variant) with the error columns of
    :func:`run_case`.
    """
    import pandas as pd

    cfg = validation_config(cfg) if "grid" not in (cfg or {}) else cfg
    cases = [Case.of(c) for c in (cases or cfg["ablation"]["cases"])]
    variants = variants or cfg["ablation"]["variants"]
    items = [(cfg, c, dict(v)) for c in cases for v in variants.values()]
    names = [name for c in cases for name in variants]
    results = _map(_run_case_worker, items, processes)
    rows = []
    for name, res in zip(names, results):
        rows.append({"variant": name, **res.row})
    return pd.DataFrame(rows)


# ----------------------------------------------------------------------------
# plots
# ----------------------------------------------------------------------------


def _save(fig, paths) -> list[Path]:
    from ..plotting import save_atomic

    out = []
    for p in paths:
        save_atomic(fig, p)
        out.append(Path(p))
    return out


SYNTH_NOTE = "synthetic: virtual rig vs Eq. (4) model -- not the paper's measurements"


def plot_fig3(data: dict, paths) -> list[Path]:
    """Fig. 3 analogue: (a) delta vs amplitude of the bare structure's free decays; (b) sweep + half-power."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    dec = data["decay"]
    rig = dec[dec.source == "rig"]
    ax1.plot(rig.amplitude_mm, rig.delta, ".", ms=3, color="C0", label="virtual rig (per cycle)")
    ax1.axhline(data["delta_exact"], color="k", lw=1.2, label=f"model δ = {data['delta_exact']:.4f}")
    ax1.axhline(data["delta_mean"]["rig"], color="C0", ls="--", lw=1,
                label=f"rig mean δ = {data['delta_mean']['rig']:.4f}")
    ax1.axvline(5.0, color="0.6", ls=":", lw=1)
    ax1.set_xlabel("displacement amplitude [mm]")
    ax1.set_ylabel("log decrement δ")
    ax1.set_title("(a) bare structure, free vibration")
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    sc = data["steady_curve"]
    ax2.plot(sc["r"], sc["amp_mm"], "-", color="k", lw=1, label="model, steady state")
    styles = {"paper_grid": ("o", "C1"), "fine_grid": (".", "C0")}
    for g, sw in data["sweeps"].items():
        m, c = styles[g]
        hp = sw["half_power"]["rig"]
        lab = f"rig, step {sw['step']:g}: " + (f"β_hp = {hp['beta']:.5f}" if hp["resolved"] else "β unresolved")
        ax2.plot(sw["r"], sw["rig_amp_mm"], m, ms=4, color=c, mfc="none", label=lab)
    ax2.set_xlabel("frequency ratio r")
    ax2.set_ylabel("√2·RMS amplitude [mm]")
    ax2.set_title("(b) bare structure, forced vibration")
    ax2.set_xlim(0.97, 1.03)
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    fig.suptitle(SYNTH_NOTE, fontsize=8)
    fig.tight_layout()
    out = _save(fig, paths)
    plt.close(fig)
    return out


def plot_fig5(data: dict, paths) -> list[Path]:
    """Fig. 5 analogue: (a) delta - delta_bare vs amplitude (steel walls); (b) sweep (1.0 mm rubber)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    a = data["a"]["data"]
    for who, m, c in (("rig", ".", "C0"), ("model", "x", "C3")):
        sel = (a.source == who) & (a.system == "pid")
        ax1.plot(a.loc[sel, "amplitude_mm"], a.loc[sel, "delta_minus_bare"], m, ms=3, color=c,
                 label=f"{who}, with PID")
        sel = (a.source == who) & (a.system == "bare")
        ax1.plot(a.loc[sel, "amplitude_mm"], a.loc[sel, "delta_minus_bare"], m, ms=2, color="0.6",
                 label=f"{who}, bare" if who == "rig" else None)
    ax1.axhline(0.0, color="k", lw=0.8)
    ax1.set_xlabel("displacement amplitude [mm]")
    ax1.set_ylabel("δ − δ_bare")
    ax1.set_title(f"(a) free vibration, {data['a']['case']}")
    ax1.legend(fontsize=7)
    ax1.grid(alpha=0.3)
    b = data["b"]["data"].sort_values("r")
    ax2.plot(b.r, b.model_amp_mm, "-", color="C3", lw=1.2, label="model Eq. (4)")
    ax2.plot(b.r, b.rig_amp_mm, "o", ms=4, mfc="none", color="C0", label="virtual rig")
    beat = b.rig_beating.astype(bool)
    ax2.plot(b.r[beat], b.rig_amp_mm[beat], "o", ms=4, color="C0", label="rig record beats")
    for r_show in data["b"]["histories"]:
        ax2.axvline(r_show, color="0.7", ls=":", lw=1)
    ax2.set_xlabel("frequency ratio r")
    ax2.set_ylabel("√2·RMS amplitude [mm]")
    ax2.set_title(f"(b) forced vibration, {data['b']['case']}")
    ax2.legend(fontsize=7)
    ax2.grid(alpha=0.3)
    fig.suptitle(SYNTH_NOTE, fontsize=8)
    fig.tight_layout()
    out = _save(fig, paths)
    plt.close(fig)
    return out


def plot_histories(data: dict, paths) -> list[Path]:
    """Fig. 4 analogue: the rig's and the model's records at the Fig. 5(b) extra points."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    hist = data["b"]["histories"]
    n = max(len(hist), 1)
    fig, axes = plt.subplots(n, 1, figsize=(9, 2.2 * n), squeeze=False)
    for ax, (r_show, h) in zip(axes[:, 0], sorted(hist.items())):
        ax.plot(h["rig"]["t"], h["rig"]["x"], lw=0.5, color="C0", label="virtual rig")
        ax.plot(h["model"]["t"], h["model"]["x"], lw=0.5, color="C3", alpha=0.7, label="model")
        ax.set_ylabel("x [mm]")
        ax.set_title(f"r = {r_show:g}", fontsize=9)
    axes[-1, 0].set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=7, loc="upper right")
    fig.suptitle(SYNTH_NOTE, fontsize=8)
    fig.tight_layout()
    out = _save(fig, paths)
    plt.close(fig)
    return out


# ----------------------------------------------------------------------------
# the stage
# ----------------------------------------------------------------------------


def _write_text(path: Path, text: str) -> None:
    from ..io import write_text_atomic

    write_text_atomic(path, text)


def write_csv(df, path) -> Path:
    """Write a DataFrame as CSV atomically."""
    path = Path(path)
    _write_text(path, df.to_csv(index=False))
    return path


def _write_records(folder: Path, prefix: str, recs: Iterable[Record]) -> None:
    for rec in recs:
        h = rec.header
        tag = f"r{h['r']:.4f}" if "r" in h else (f"x0_{h['x0_mm']:g}mm" if "x0_mm" in h else "drops")
        src = "rig" if h.get("source", "").startswith("virtual rig") else "model"
        write_record(folder / prefix / f"{src}_{h['kind']}_{tag}.csv", rec)


def drop_tests(cfg: dict) -> tuple[list[Record], "Any"]:
    """Synthetic drop-test records for every ball and wall, and e recovered by Eq. (3b)."""
    import pandas as pd

    from .analysis import drop_test_restitution

    recs, rows = [], []
    for wall in cfg["grid"]["walls"]:
        for mu in cfg["grid"]["mu"]:
            rec = R.drop_test_record(cfg, wall, mu, seed=R.seed_for("drop", wall, mu, base=cfg.get("seed", 0)))
            e_rec = drop_test_restitution(rec)
            recs.append(rec)
            for hd, er in zip(rec.drop_height_cm, e_rec):
                rows.append({"wall": wall, "mu": mu, "drop_height_cm": float(hd), "e_calibrated": wall_e(cfg, wall),
                             "e_recovered": float(er)})
    return recs, pd.DataFrame(rows)


def run_validation(cfg: dict | None, out_dir, cases=None, *, smoke: bool = False, processes: int | None = None,
                   figures: bool = True, write_all_records: bool = False, ablate: bool = False):
    """The cross-validation stage.

    Runs every case (default: the whole grid; ``smoke=True``: the smoke subset
    with its shortened protocol; or the given ``cases``: Case objects, ids or
    dicts), in ``processes`` worker processes, and writes into ``out_dir``:

    * ``validation_table.csv`` -- one row per case (errors, peaks, half-power,
      AIPC, beating, timings),
    * ``validation_curves.csv`` -- per case and r: both amplitudes, AIPC,
      modulation, beating,
    * ``validation_delta.csv`` -- per case and amplitude bin: both delta,
    * ``drop_tests.csv`` and ``records/drop_tests/*.csv`` -- synthetic drop tests,
    * ``claims.json`` -- :func:`evaluate_claims` plus timings,
    * with ``figures``: ``fig3.{png,pdf}``, ``fig5.{png,pdf}``, ``fig4_histories.png``,
      their data (``fig3_*.csv``, ``fig5_*.csv``) and the records behind them
      under ``records/``;
    * with ``ablate``: ``ablation.csv`` (:func:`ablation` on ``ablation.cases``);
    * with ``write_all_records``: every record of the grid under ``records/grid/``
      (about 1 GB for the full grid -- off by default).

    Returns the table (pandas DataFrame).
    """
    import pandas as pd

    t_start = time.perf_counter()
    cfg = validation_config(cfg, smoke=smoke)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if cases is None:
        cases = cfg["smoke"]["cases"] if smoke else all_cases(cfg)
    cases = [Case.of(c) for c in cases]
    nproc = int(processes if processes is not None else cfg.get("processes", 1))
    t0 = time.perf_counter()
    results = _map(_run_case_worker, [(cfg, c, None) for c in cases], nproc)
    t_grid = time.perf_counter() - t0
    table = pd.DataFrame([r.row for r in results])
    curves = pd.DataFrame([row for r in results for row in r.curve])
    delta = pd.DataFrame([row for r in results for row in r.delta])
    write_csv(table, out / "validation_table.csv")
    write_csv(curves, out / "validation_curves.csv")
    write_csv(delta, out / "validation_delta.csv")
    drec, ddf = drop_tests(cfg)
    write_csv(ddf, out / "drop_tests.csv")
    for rec in drec:
        write_record(out / "records" / "drop_tests" /
                     f"rig_drop_{rec.header['wall']}_D{rec.header['ball_diameter_mm']:g}mm.csv", rec)
    f3 = f5 = None
    if figures:
        f3 = fig3_data(cfg, keep_records=True)
        f5 = fig5_data(cfg, keep_records=True)
        plot_fig3(f3, [out / "fig3.png", out / "fig3.pdf"])
        plot_fig5(f5, [out / "fig5.png", out / "fig5.pdf"])
        plot_histories(f5, [out / "fig4_histories.png"])
        write_csv(f3["decay"], out / "fig3a_decay.csv")
        rows = []
        for g, sw in f3["sweeps"].items():
            for r, am, ar in zip(sw["r"], sw["model_amp_mm"], sw["rig_amp_mm"]):
                rows.append({"grid": g, "r": r, "model_amp_mm": am, "rig_amp_mm": ar})
        write_csv(pd.DataFrame(rows), out / "fig3b_sweep.csv")
        write_csv(f5["a"]["data"], out / "fig5a_decay.csv")
        write_csv(f5["b"]["data"], out / "fig5b_sweep.csv")
        recdir = out / "records"
        for who in ("model", "rig"):
            _write_records(recdir, "fig3a", f3["records"]["decay"][who])
            for g in ("paper_grid", "fine_grid"):
                _write_records(recdir, f"fig3b_{g}", f3["records"]["sweep"][g][who])
            _write_records(recdir, "fig5a_pid", f5["records"]["fig5a_pid"][who])
            _write_records(recdir, "fig5a_bare", f5["records"]["fig5a_bare"][who])
            _write_records(recdir, "fig5b", f5["records"]["fig5b"][who])
    if write_all_records:
        for c in cases:
            res = run_case(cfg, c, keep_records=True)
            for who in ("model", "rig"):
                _write_records(out / "records" / "grid", c.id, res.records["sweep"][who])
                _write_records(out / "records" / "grid", c.id, res.records["decay"][who])
    if ablate:
        write_csv(ablation(cfg, processes=nproc), out / "ablation.csv")
    claims = evaluate_claims(cfg, table, curves, f3, f5)
    claims["drop_tests"] = {"max_abs_error_e": float(np.max(np.abs(ddf.e_recovered - ddf.e_calibrated))),
                            "note": "Eq. (3b) with the header's mu on synthetic drops"}
    claims["run"] = {"cases": len(cases), "processes": nproc, "grid_seconds": t_grid,
                     "total_seconds": time.perf_counter() - t_start, "smoke": smoke,
                     "synthetic": True, "source": "virtual rig vs Eq. (4) model; not the paper's data"}
    _write_text(out / "claims.json", json.dumps(_jsonable(claims), indent=2, sort_keys=True) + "\n")
    return table


purge_stale_cache(_model_samples, "impact-experiment")
