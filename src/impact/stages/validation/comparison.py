"""Model against rig, case by case: the cross-validation of Eq. (4) (the paper's Sect. 3, Figs. 3--5).

For every case of the paper's experimental grid (mu x d x r' x wall, 108
cases) the **model** -- Eq. (4) as simulated by the production exact
event-driven kernel (:mod:`impact.engine.paper` / :mod:`impact.engine.paper_loop`: linear
pendulum, instantaneous Newton impacts, model units M = 1, omega = 1, lengths
in mm) -- and the **virtual rig** (:mod:`impact.rig.simulator`: nonlinear
compound pendulum, finite ball, Hunt--Crossley contact calibrated to e, sensor
range and noise) are run under the same protocol, both are written as records
of the experiment data format (``synthetic: true``, with their provenance),
and both go through the *same* analysis code
(:mod:`impact.outputs.signals`):

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
(:func:`run_case`); over the grid a table (:mod:`.steps`), the paper's
claims as the rig and the model see them (:mod:`.claims`), the data of
Figs. 3 and 5 (:func:`fig3_data`, :func:`fig5_data`) and their plots (:mod:`.plotting`).  The
rig's fidelity features can be switched off one at a time
(:func:`ablation`) to see which one dominates the model-rig differences.

Nothing here is the paper's data: every record says ``synthetic: true`` and
names its generator in ``source``.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from impact.model.kinds import PID
from impact.outputs.measurements import Measurement
from impact.outputs.signals import (
    UnresolvedPeakError,
    beta_to_delta,
    count_impacts,
    drop_test_restitution,
    half_power,
    impacts_per_cycle,
    log_decrement,
    sweep_curve,
    whole_periods,
)
from impact.rig import simulator as R
from impact.rig.config import merge, validation_config
from impact.stages.validation.grid import Case, frequency_values, wall_e
from impact.stages.validation.paper_model import (
    model_bare_forced_point,
    model_bare_free_decay,
    model_forced_point,
    model_free_decay,
    warm_up_model,
)

# ----------------------------------------------------------------------------
# the rig, with the validation's protocol
# ----------------------------------------------------------------------------


def _rig(cfg: dict, case: Case | None, fidelity: dict | None) -> tuple[R.RigSpec, str]:
    """The rig of a case (None: the bare structure) and the case's name in the seeds."""
    fid = fidelity or {}
    if case is None:
        return R.rig_spec(cfg, bare=True, **fid), "bare"
    return R.rig_spec(cfg, mu=case.mu, gap_mm=case.gap_mm, rp=case.rp, wall=case.wall, **fid), case.id


def rig_forced_point(cfg: dict, case: Case | None, r: float, *, fidelity: dict | None = None,
                     settle_periods: float | None = None, record_periods: float | None = None) -> R.RigOutput:
    spec, cid = _rig(cfg, case, fidelity)
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
    spec, cid = _rig(cfg, case, fidelity)
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


def _clip_end_time(rec: Measurement, range_mm: float | None) -> float | None:
    """Time from which a record is free of sensor saturation (one period after the last clipped sample)."""
    if range_mm is None:
        return None
    x = rec.x_in("mm")
    clipped = np.flatnonzero(np.abs(x) >= range_mm * (1.0 - 1e-9))
    if clipped.size == 0:
        return None
    T = 1.0 / float(rec.header.get("structure_hz", 1.5))
    return float(rec.t[clipped[-1]] + T)


def decay_points(rec: Measurement, *, t_start: float | None = None, min_amplitude: float | None = None) -> dict:
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


def _aipc(rec: Measurement, d_mm: float, forcing_hz: float) -> float:
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

    warm_up()
    ctx = mp.get_context("fork")
    with ctx.Pool(processes) as pool:
        return pool.map(fn, items, chunksize=1)


def warm_up() -> None:
    """Compile (or load from cache) every kernel the validation uses."""
    R.warm_up()
    warm_up_model()


# ----------------------------------------------------------------------------
# bare structure (Fig. 3), the Fig. 5 cases, the drop tests
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
    cfg = merge(cfg, {"excitation": {"force_ratio_mm": float(b.get("force_ratio_mm",
                                                                    cfg["excitation"]["force_ratio_mm"]))}})
    dc = decay_pair(cfg, None, b["decay_x0_mm"], float(b["decay_duration_s"]), keep=keep_records)
    decay_rows = []
    for who in ("model", "rig"):
        for p in dc["points"][who]:
            for a, d in zip(p["amplitude"], p["delta"]):
                decay_rows.append({"source": who, "x0_mm": p["x0_mm"], "amplitude_mm": float(a), "delta": float(d)})

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
        for system, dd in ((PID, pid), ("bare", bare)):
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


def drop_tests(cfg: dict) -> tuple[list[Measurement], "Any"]:
    """Synthetic drop-test records for every ball and wall, and e recovered by Eq. (3b)."""

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


def ablation(cfg: dict | None = None, cases=None, variants: dict | None = None, processes: int = 1):
    """Model-vs-rig errors with the rig's fidelity features switched off one at a time.

    Returns a DataFrame: one row per (case, variant) with the error columns of
    :func:`run_case`.
    """

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
