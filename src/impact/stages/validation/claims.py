"""The paper's Sect. 3 claims, as the virtual rig and the model see them.

Each claim is stated as the paper makes it, with the numbers of both sources and whether they
support it.  Everything here is synthetic: the rig is a simulation, not the paper's measurements.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from impact.stages.validation.grid import wall_e


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
    return jsonable(claims)


def jsonable(obj, *, keep_nan: bool = False):
    """Numbers and arrays as JSON values; a non-finite float as null (strict JSON), or kept (keep_nan)."""
    if isinstance(obj, dict):
        return {str(k): jsonable(v, keep_nan=keep_nan) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [jsonable(v, keep_nan=keep_nan) for v in (obj.tolist() if isinstance(obj, np.ndarray) else obj)]
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        return v if keep_nan or math.isfinite(v) else None
    return obj
