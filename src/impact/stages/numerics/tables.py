"""The numerics stage's tables: the work-precision pieces joined, speed at equal error, the stability
table and its verdicts (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from impact.outputs.files import as_integers, flag
from impact.stages.numerics.plan import (
    Timeout,
    extreme_cases,
    method_ladders,
    stability_methods,
    work_precision_cases,
)

WORK_PRECISION_ATTRS = ("reference", "k_impacts", "wall_time", "repeats", "budget_seconds", "budget_over_core")


def _outcome(out) -> str:
    if isinstance(out, Exception):
        return f"failed: {out}" if isinstance(out, Timeout) else f"failed: {type(out).__name__}: {str(out)[:120]}"
    return "ok" if out["status"] == "ok" and np.isfinite(out["amplitude"]) else str(out["status"])


#: the work-precision measures that are counts, and the flag of a failed run: integers, -1 where the run has none
WHOLE = ("nfev", "impacts", "impacts_compared", "failed")


def with_integer_counts(ds: xr.Dataset) -> xr.Dataset:
    """The counts and the failure flag as integers (read back, -1 is NaN: a run that failed has no count)."""
    ds["failed"].attrs = flag("the run failed (over its time budget, non-finite or an error)", "finished", "failed")
    return as_integers(ds, WHOLE, missing=-1)


def combine_work_precision(parts, cfg: dict) -> xr.Dataset:
    """The pieces of one study (each some cases and some families) as one dataset, in the study's order."""
    parts = list(parts)
    ds = xr.merge(parts, compat="no_conflicts", join="outer", combine_attrs="override")
    ds.attrs = {k: v for k, v in parts[0].attrs.items() if k in WORK_PRECISION_ATTRS}  # not a piece's provenance
    return with_integer_counts(ds.reindex(case=list(work_precision_cases(cfg)), integrator=list(method_ladders(cfg))))


def speed_at_equal_error(ds: xr.Dataset, error: str = "amplitude_error") -> pd.DataFrame:
    """Per case: the core's time and error, and the fastest baseline setting at least as accurate."""
    rows = []
    for case in ds["case"].values:
        core_t = float(ds["wall_time"].sel(case=case, integrator="core", setting=0))
        core_e = float(ds[error].sel(case=case, integrator="core", setting=0))
        best = (math.inf, None, math.nan)
        closest = (math.inf, None, math.nan, math.nan)
        for method in ds["integrator"].values:
            if method == "core":
                continue
            for s in ds["setting"].values:
                t = float(ds["wall_time"].sel(case=case, integrator=method, setting=s))
                e = float(ds[error].sel(case=case, integrator=method, setting=s))
                if not (math.isfinite(t) and math.isfinite(e)):
                    continue
                label = f"{method} {float(ds['setting_value'].sel(integrator=method, setting=s)):g}"
                if e <= max(core_e, 1e-12) and t < best[0]:
                    best = (t, label, e)
                if e < closest[2] or not math.isfinite(closest[2]):
                    closest = (t, label, e, t)
        rows.append({"case": str(case), "core_seconds": core_t, "core_error": core_e,
                     "fastest_baseline_at_equal_error": best[1], "its_seconds": best[0], "its_error": best[2],
                     "speed_ratio_at_equal_error": best[0] / core_t if best[1] else math.nan,
                     "most_accurate_baseline": closest[1], "its_best_error": closest[2],
                     "its_best_seconds": closest[3],
                     "speed_ratio_vs_most_accurate": closest[3] / core_t if closest[1] else math.nan})
    return pd.DataFrame(rows)


def stability_table(parts, cfg: dict) -> pd.DataFrame:
    """The runs of every family, case by case in the study's order, judged (:func:`judge_stability`)."""
    cases = extreme_cases(cfg)
    order = {name: i for i, name in enumerate(cases)}
    methods = {name: i for i, name in enumerate(stability_methods(cfg))}
    runs = pd.concat(list(parts), ignore_index=True)
    runs = runs.iloc[sorted(range(len(runs)), key=lambda i: (order[runs["case"].iloc[i]],
                                                             methods[runs["method"].iloc[i]]))]
    return judge_stability(runs.reset_index(drop=True), {case: system.gap for case, (system, _, _) in cases.items()})


# a run is ok when it finished with a finite state, kept out of the walls and agreed with the exact core
OK_PENETRATION = 1e-6  # largest penetration beyond a wall, over the gap


OK_AMPLITUDE = 1e-3    # amplitude's relative difference from the core's


def judge_stability(table: pd.DataFrame, gaps: dict) -> pd.DataFrame:
    """Add penetration_over_gap, amplitude_error (against the core's run of the case) and ok.

    ok means finished and within tolerance: penetration <= OK_PENETRATION of the gap and amplitude
    within OK_AMPLITUDE of the core's.  A run that finishes but sinks 0.3 units into a wall is not ok.
    Where the core itself gave no amplitude (it failed or hit its event cap) there is nothing to compare
    with: amplitude_error is NaN and only the penetration is judged.
    """
    table = table.copy()
    for column in ("amplitude", "max_penetration"):  # absent when every run failed
        if column not in table:
            table[column] = np.nan
    core = table[table["method"] == "core"].set_index("case")["amplitude"]
    pen = table["max_penetration"].astype(float)
    gap = table["case"].map(gaps).astype(float)
    ratio = np.where(pen <= 0.0, 0.0, pen / gap.where(gap > 0.0, np.nan))
    table["penetration_over_gap"] = np.where(np.isnan(ratio) & (pen > 0.0), np.inf, ratio)
    amp = table["amplitude"].astype(float)
    ref = table["case"].map(core).astype(float)
    table["amplitude_error"] = (amp - ref).abs() / ref.abs()
    finished = (table["status"] == "ok") & table["finite"].fillna(False).astype(bool)
    near_core = (table["amplitude_error"] <= OK_AMPLITUDE) | ref.isna()
    within = (table["penetration_over_gap"] <= OK_PENETRATION) & near_core
    table["ok"] = finished & within
    return table
