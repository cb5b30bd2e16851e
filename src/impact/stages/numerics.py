"""Numerics shown, not assumed: error against run time, and stability on extreme cases.

Work-precision: every integrator (the exact core and the baselines of
:mod:`impact.baselines`) runs the same cases over a ladder of its own setting
(tolerance, step, contact stiffness); its errors are measured against the
exact core, and its wall time is the minimum of several repeats after a
warm-up (one timed run is enough for a run longer than a second).  Every run
has a budget: over it, the run is recorded as failed, "too slow at this
setting".  The work splits into one piece per case and method family
(:data:`FAMILIES`), which the workflow runs as parallel jobs and
:func:`combine_work_precision` joins.  For the irregular (chaotic) case the predictability horizon is
measured first (runs perturbed at round-off diverge) and errors are compared
only inside it.

Stability: every method on extreme inputs (e -> 0 and 1, gap -> 0, no or tiny
damping, extreme mass ratios, a very stiff pendulum, grazing forcing, large
friction): finished or failed, finite or not, penetration, impacts per
period, wall time.  A baseline's failure is recorded, never hidden.
"""

from __future__ import annotations

import dataclasses
import math
import signal
import time

import numpy as np
import pandas as pd
import xarray as xr

from impact.baselines import simulate_ivp, simulate_moreau_jean, simulate_penalty, simulate_rk4
from impact.engine.paper import simulate
from impact.model.params import Protocol, System, a_max
from impact.outputs.labels import TOO_SLOW

K_IMPACTS = 20
# methods that differ only in a setting or a solver option run as one piece of work
FAMILIES = ("core", "ivp", "rk4", "moreau_jean", "penalty")
ONE_REPEAT_ABOVE = 1.0  # s: a run this long is timed once; shorter runs keep the minimum of the repeats
DEFAULT_BUDGET = 10.0  # s per run (the configuration's numerics.budget)


def family(method: str) -> str:
    """The family of a method: ivp for every solve_ivp method, else the method itself."""
    return "ivp" if method.startswith("ivp_") else method


# --------------------------------------------------------------------------- cases and methods

def work_precision_cases(cfg: dict) -> dict:
    """Name -> (system, r, start, natural periods) of the work-precision cases."""
    paper = dict(mu=0.01, beta=0.0048, e=0.25)
    periods = float(cfg.get("periods", 40))
    return {
        "cid_2eipc": (System.from_gap_ratio("cid", gap_ratio=1.6, **paper), 1.0, "left", periods),
        "cid_irregular": (System.from_gap_ratio("cid", mu=0.01, beta=0.0048, e=0.65, gap_ratio=0.5), 0.97,
                          "centre", periods),
        "pid_tuned": (System.from_gap_ratio("pid", gap_ratio=1.0, rp=1.0, **paper), 1.0, "centre", periods),
        "cid_friction": (System.from_gap_ratio("cid", gap_ratio=1.6, nu=0.05, **paper), 1.0, "left", periods),
    }


def method_ladders(cfg: dict) -> dict:
    """Method -> (setting name, list of settings), from the configuration."""
    ladders = {"core": ("exact", [0.0])}
    for method in cfg.get("ivp_methods", ["RK45", "DOP853", "Radau", "LSODA"]):
        ladders[f"ivp_{method}"] = ("rtol", list(cfg.get("rtol", [1e-4, 1e-6, 1e-8, 1e-10])))
    ladders["rk4"] = ("steps_per_period", list(cfg.get("steps_per_period", [50, 100, 200, 400])))
    ladders["moreau_jean"] = ("steps_per_period", list(cfg.get("steps_per_period", [50, 100, 200, 400])))
    ladders["penalty"] = ("stiffness", list(cfg.get("stiffness", [1e3, 1e4, 1e5])))
    return ladders


def run_method(method: str, setting: float, system: System, r: float, start: str, t_end: float, t_window: float):
    """One run of one method; returns a common record (dict)."""
    period = 2.0 * math.pi
    if method == "core":
        res = simulate(system, r, Protocol(periods=t_end / period, average_from=t_window / period, start=start),
                       record=K_IMPACTS)
        rec = res.records
        return {"impact_times": rec["t"], "post": np.column_stack([rec["v_plus"], rec["w_plus"]]),
                "final_state": res.final_state, "amplitude": res.amplitude, "nfev": 0,
                "impacts": res.diagnostics["impacts"], "max_penetration": res.diagnostics["max_penetration"],
                "energy_residual": res.diagnostics["energy_residual"], "status": "ok"}
    if method.startswith("ivp_"):
        out = simulate_ivp(system, r, t_end, t_window, start, method=method[4:], rtol=setting)
    elif method == "rk4":
        out = simulate_rk4(system, r, t_end, t_window, start, dt=period / setting)
    elif method == "moreau_jean":
        out = simulate_moreau_jean(system, r, t_end, t_window, start, dt=period / setting)
    elif method == "penalty":
        out = simulate_penalty(system, r, t_end, t_window, start, stiffness=setting)
    else:
        raise ValueError(f"unknown method {method!r}")
    return {"impact_times": out.impact_times, "post": out.post, "final_state": out.final_state,
            "amplitude": out.amplitude, "nfev": out.nfev, "impacts": len(out.impact_times),
            "max_penetration": out.max_penetration, "energy_residual": math.nan, "status": out.status}


class Timeout(Exception):
    pass


def _on_alarm(signum, frame):
    raise Timeout()


def timed(fun, limit: float):
    """(seconds, result or exception) of fun(), stopped after `limit` seconds (SIGALRM).

    A run stopped by the limit gives a Timeout whose message is TOO_SLOW.  (The alarm reaches a
    compiled kernel only when it returns to Python: a run inside one long numba call can overrun.)
    """
    old = signal.signal(signal.SIGALRM, _on_alarm)
    signal.setitimer(signal.ITIMER_REAL, limit)
    t0 = time.perf_counter()
    try:
        out = fun()
    except Timeout:
        out = Timeout(f"{TOO_SLOW} (no result within the {limit:g} s budget)")
    except Exception as exc:  # a baseline that fails is a result, recorded below
        out = exc
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)
    return time.perf_counter() - t0, out


def timed_repeats(fun, limit: float, repeats: int):
    """(best seconds, result or exception): the minimum of `repeats` runs, or of one if it takes over
    ONE_REPEAT_ABOVE; the first failure ends it."""
    best, out = math.inf, None
    for _ in range(repeats):
        seconds, got = timed(fun, limit)
        if isinstance(got, Exception):
            return seconds, got
        best, out = min(best, seconds), got
        if seconds > ONE_REPEAT_ABOVE:
            break
    return best, out


def budget(cfg: dict) -> float:
    return float(cfg.get("budget", DEFAULT_BUDGET))


# --------------------------------------------------------------------------- error measures

def predictability_horizon(system: System, r: float, start: str, t_max: float, threshold: float = 1e-3) -> float:
    """Time after which runs perturbed at round-off (1e-15) differ by more than threshold * amplitude."""
    base = simulate(system, r, Protocol(periods=t_max / (2 * math.pi), average_from=0.0, start=start), record=200000)
    times = base.records["t"]
    if len(times) < 2:
        return t_max
    perturbed = dataclasses.replace(system, phase=system.phase + 1e-15)
    other = simulate(perturbed, r, Protocol(periods=t_max / (2 * math.pi), average_from=0.0, start=start),
                     record=200000)
    n = min(len(times), len(other.records["t"]))
    scale = max(float(np.max(np.abs(base.records["x"][:n]))), 1e-300)
    diff = np.abs(base.records["t"][:n] - other.records["t"][:n]) + np.abs(base.records["x"][:n]
                                                                          - other.records["x"][:n]) / scale
    far = np.nonzero(diff > threshold)[0]
    return float(times[far[0]]) if far.size else t_max


def errors(run: dict, ref: dict, k: int = K_IMPACTS) -> dict:
    """Impact-time, post-impact-velocity, final-state and amplitude errors against the reference."""
    n = min(k, len(run["impact_times"]), len(ref["impact_times"]))
    vel_scale = max(float(np.max(np.abs(ref["post"][:n]))) if n else 1.0, 1e-300)
    state_scale = max(float(np.max(np.abs(ref["final_state"]))), 1e-300)
    return {
        "impact_time_error": float(np.max(np.abs(run["impact_times"][:n] - ref["impact_times"][:n]))) if n else math.nan,
        "velocity_error": float(np.nanmax(np.abs(run["post"][:n] - ref["post"][:n]))) / vel_scale if n else math.nan,
        "state_error": float(np.max(np.abs(np.asarray(run["final_state"]) - ref["final_state"]))) / state_scale,
        "amplitude_error": abs(run["amplitude"] - ref["amplitude"]) / abs(ref["amplitude"]),
        "impacts_compared": n,
        "impact_count_differs": int(run["impacts"] != ref["impacts"]),
    }


# --------------------------------------------------------------------------- work-precision

def work_precision(cfg: dict, cases=None, families=None, log=None) -> xr.Dataset:
    """Every method of `families` (default: all) on `cases` (default: all), as a dataset.

    Dimensions case x integrator x setting; the setting axis is as long as the longest ladder of
    all methods, so that the pieces of one study join (:func:`combine_work_precision`).
    """
    all_cases = work_precision_cases(cfg)
    cases = {name: all_cases[name] for name in (cases or all_cases)}
    ladders = method_ladders(cfg)
    nset = max(len(v[1]) for v in ladders.values())
    methods = [m for m in ladders if families is None or family(m) in families]
    names = ("wall_time", "impact_time_error", "velocity_error", "state_error", "amplitude_error",
             "nfev", "impacts", "impacts_compared", "failed")
    data = {n: np.full((len(cases), len(methods), nset), np.nan) for n in names}
    status = np.full((len(cases), len(methods), nset), "", dtype=object)
    setting_value = np.full((len(methods), nset), np.nan)
    horizon = {}
    repeats = int(cfg.get("repeats", 3))
    limit = budget(cfg)
    for ic, (case, (system, r, start, periods)) in enumerate(cases.items()):
        t_end = 2 * math.pi * periods
        # compare only inside the predictability horizon: the irregular case, but
        # also stick-slip with friction, amplify round-off differences
        horizon[case] = predictability_horizon(system, r, start, t_end)
        if horizon[case] < t_end:
            t_end = 0.5 * horizon[case]
        else:
            horizon[case] = math.inf
        t_window = 0.5 * t_end
        ref = run_method("core", 0.0, system, r, start, t_end, t_window)
        for im, method in enumerate(methods):
            for iset, setting in enumerate(ladders[method][1]):
                setting_value[im, iset] = setting
                run_method(method, setting, system, r, start, min(t_end, 2 * math.pi), 0.5)  # warm-up
                best, out = timed_repeats(lambda: run_method(method, setting, system, r, start, t_end, t_window),
                                          limit, repeats)
                failed = isinstance(out, Exception) or out["status"] != "ok" or not np.isfinite(out["amplitude"])
                data["failed"][ic, im, iset] = float(failed)
                status[ic, im, iset] = _outcome(out)
                if isinstance(out, Exception):
                    if log:
                        log.info("%s %s %g failed: %s", case, method, setting, out)
                    continue
                data["wall_time"][ic, im, iset] = best
                data["nfev"][ic, im, iset] = out["nfev"]
                data["impacts"][ic, im, iset] = out["impacts"]
                for key, value in errors(out, ref).items():
                    if key in data:
                        data[key][ic, im, iset] = value
                if log:
                    log.info("%s %s %g: %.3g s, amplitude error %.2g", case, method, setting, best,
                             data["amplitude_error"][ic, im, iset])
    # "integrator", not "method": xarray's .sel() has a keyword of that name
    dims = ("case", "integrator", "setting")
    units = {"wall_time": "s"}
    ds = xr.Dataset({n: (dims, v, {"units": units.get(n, "1"), "long_name": n.replace("_", " ")})
                     for n, v in data.items()},
                    coords={"case": ("case", list(cases), {"long_name": "test case"}),
                            "integrator": ("integrator", methods, {"long_name": "integration method"}),
                            "setting": ("setting", np.arange(nset),
                                        {"units": "1", "long_name": "index of the method setting on its ladder"})})
    ds["status"] = (dims, status.astype(str), {
        "long_name": "outcome of the run: ok, the reason it failed, or empty past the end of a ladder"})
    ds["setting_value"] = (("integrator", "setting"), setting_value, {
        "units": "1", "long_name": "method setting: rtol, steps per natural period, or contact stiffness"})
    ds["setting_name"] = ("integrator", [ladders[m][0] for m in methods], {"long_name": "what the setting is"})
    ds["predictability_horizon"] = ("case", [horizon[c] for c in cases], {
        "units": "1", "long_name": "dimensionless time (Omega t) after which round-off-perturbed runs differ by 1e-3"})
    ds.attrs.update(reference="the exact event-driven core (impact.engine.paper)", k_impacts=K_IMPACTS,
                    wall_time=f"minimum of {repeats} repeats after a warm-up (one for a run over "
                              f"{ONE_REPEAT_ABOVE:g} s)", repeats=repeats, budget_seconds=limit)
    return ds


WORK_PRECISION_ATTRS = ("reference", "k_impacts", "wall_time", "repeats", "budget_seconds")


def _outcome(out) -> str:
    if isinstance(out, Exception):
        return f"failed: {out}" if isinstance(out, Timeout) else f"failed: {type(out).__name__}: {str(out)[:120]}"
    return "ok" if out["status"] == "ok" and np.isfinite(out["amplitude"]) else str(out["status"])


def combine_work_precision(parts, cfg: dict) -> xr.Dataset:
    """The pieces of one study (each some cases and some families) as one dataset, in the study's order."""
    parts = list(parts)
    ds = xr.merge(parts, compat="no_conflicts", join="outer", combine_attrs="override")
    ds.attrs = {k: v for k, v in parts[0].attrs.items() if k in WORK_PRECISION_ATTRS}  # not a piece's provenance
    return ds.reindex(case=list(work_precision_cases(cfg)), integrator=list(method_ladders(cfg)))


def work_precision_pieces(cfg: dict) -> list[tuple[str, str]]:
    """(case, family) of every piece of work of the study."""
    families = {family(m) for m in method_ladders(cfg)}
    return [(case, fam) for case in work_precision_cases(cfg) for fam in FAMILIES if fam in families]


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


# --------------------------------------------------------------------------- stability

def extreme_cases(cfg: dict) -> dict:
    """Name -> (system, r, start) of the stiff and extreme cases (those named in cfg's stability_cases, if
    given)."""
    cases = _all_extreme_cases()
    chosen = cfg.get("stability_cases")
    if chosen is None:
        return cases
    unknown = sorted(set(chosen) - set(cases))
    if unknown:
        raise ValueError(f"numerics.stability_cases: unknown case(s) {unknown}; allowed: {list(cases)}")
    return {name: case for name, case in cases.items() if name in chosen}


def _all_extreme_cases() -> dict:
    base = dict(mu=0.01, beta=0.0048, e=0.25)

    def cid(**kw):
        g = kw.pop("gap_ratio", 1.0)
        return System.from_gap_ratio("cid", gap_ratio=g, **{**base, **kw})

    amax = a_max(0.0048, 0.096)
    bare = 0.096 / math.hypot(1 - 0.95 ** 2, 2 * 0.0048 * 0.95)  # bare amplitude at r = 0.95
    return {
        "e=0": (cid(e=0.0), 1.0, "centre"),
        "e=1e-3": (cid(e=1e-3), 1.0, "centre"),
        "e=0.999": (cid(e=0.999), 1.0, "centre"),
        "e=1": (cid(e=1.0), 1.0, "centre"),
        "g=1e-3": (cid(gap_ratio=1e-3), 1.0, "centre"),
        "g=1e-6": (cid(gap_ratio=1e-6), 1.0, "centre"),
        "beta=0": (System("cid", mu=0.01, beta=0.0, e=0.25, gap=1.0), 0.97, "centre"),
        "beta=1e-5": (System("cid", mu=0.01, beta=1e-5, e=0.25, gap=1.0), 1.0, "centre"),
        "mu=1e-4": (cid(mu=1e-4), 1.0, "centre"),
        "mu=0.5": (cid(mu=0.5), 1.0, "centre"),
        "stiff pendulum r'=100": (System.from_gap_ratio("pid", gap_ratio=1e-3, rp=100.0, **base), 1.0, "left"),
        # the damper mass rests against the left wall and the structure's steady swing
        # just reaches the right wall: grazing contact
        "grazing": (System("cid", mu=1e-6, beta=0.0048, e=0.5, gap=2 * bare * (1 + 1e-9)), 0.95, "centre"),
        "friction nu=5": (cid(nu=5.0, gap_ratio=1.6), 1.0, "left"),
    } | ({} if amax else {})


def stability_methods(cfg: dict) -> dict:
    """One mid-range setting per method for the stability table."""
    return {"core": 0.0, "ivp_RK45": 1e-8, "ivp_DOP853": 1e-8, "ivp_Radau": 1e-8, "ivp_LSODA": 1e-8,
            "rk4": 200, "moreau_jean": 200, "penalty": 1e5} | cfg.get("stability_settings", {})


def stability_runs(cfg: dict, families=None, log=None) -> pd.DataFrame:
    """Every method of `families` (default: all) on every extreme case, one row per run, not yet judged."""
    periods = float(cfg.get("stability_periods", 50))
    limit = budget(cfg)
    t_end = 2 * math.pi * periods
    rows = []
    methods = {m: v for m, v in stability_methods(cfg).items() if families is None or family(m) in families}
    for case, (system, r, start) in extreme_cases(cfg).items():
        if "core" in methods:  # compile, or load from the cache, outside the budget: a cold cache is no slowness
            run_method("core", 0.0, system, r, start, 2 * math.pi, math.pi)
        for method, setting in methods.items():
            seconds, out = timed(lambda: run_method(method, setting, system, r, start, t_end, 0.5 * t_end), limit)
            row = {"case": case, "method": method, "setting": setting, "wall_time": seconds}
            if isinstance(out, Exception):
                row.update(status=_outcome(out), finite=False)
            else:
                state = np.asarray(out["final_state"], dtype=float)
                finite = bool(np.all(np.isfinite(state)) and np.isfinite(out["amplitude"]))
                row.update(status=out["status"], finite=finite,
                           max_penetration=float(out["max_penetration"]),
                           energy_residual=out["energy_residual"],
                           impacts_per_period=out["impacts"] / periods,
                           amplitude=out["amplitude"])
            if log:
                log.info("%s %s: %s (%.2f s)", case, method, row["status"], seconds)
            rows.append(row)
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


def stability(cfg: dict, log=None) -> pd.DataFrame:
    """Every method on every extreme case, judged: the stability table in one piece."""
    return stability_table([stability_runs(cfg, log=log)], cfg)


def stability_families(cfg: dict) -> list[str]:
    """The families of the stability table's methods, one piece of work each."""
    present = {family(m) for m in stability_methods(cfg)}
    return [fam for fam in FAMILIES if fam in present]


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
