"""The numerics stage's runs: every integrator timed against the exact engine, and the stiff and extreme
cases."""

from __future__ import annotations

import dataclasses
import math
import signal
import time

import numpy as np
import pandas as pd
import xarray as xr

from impact.baselines import simulate_ivp, simulate_moreau_jean, simulate_penalty, simulate_rk4
from impact.engine.run import simulate_system as simulate
from impact.model.params import Protocol, System
from impact.outputs.labels import TOO_SLOW
from impact.stages.numerics.plan import (
    DEFAULT_BUDGET_OVER_CORE,
    K_IMPACTS,
    Timeout,
    budget,
    extreme_cases,
    family,
    method_ladders,
    repeat_below,
    run_budget,
    stability_methods,
    work_precision_cases,
)
from impact.stages.numerics.tables import (
    _outcome,
    stability_table,
    with_integer_counts,
)


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



def _on_alarm(signum, frame):
    raise Timeout()


def timed(fun, limit: float):
    """(wall seconds, result or exception) of fun(), stopped after `limit` seconds of the process's CPU time.

    The budget counts CPU time (ITIMER_PROF), not wall time: whether a run is "too slow" is the method's cost,
    not the load other processes put on the machine (on 2 cores running 4 jobs, wall time doubles, and a run at
    a third of its budget failed for time).  The process computes on one thread (impact.kernels pins BLAS to
    one), so its CPU time is the run's.  A run stopped by the limit gives a Timeout whose message is TOO_SLOW.
    (The alarm reaches a compiled kernel only when it returns to Python: a run inside one long numba call can
    overrun.)
    """
    old = signal.signal(signal.SIGPROF, _on_alarm)
    t0 = time.perf_counter()
    try:
        # inside the try: a limit of microseconds can ring before the next statement (0 would switch it off)
        signal.setitimer(signal.ITIMER_PROF, max(limit, 1e-6))
        out = fun()
    except Timeout:
        out = Timeout(f"{TOO_SLOW} (no result within the {limit:g} s budget of CPU time)")
    except Exception as exc:  # a baseline that fails is a result, recorded below
        out = exc
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0.0)
        signal.signal(signal.SIGPROF, old)
    return time.perf_counter() - t0, out


def timed_repeats(fun, limit: float, repeats: int, once_above: float):
    """(best seconds, result or exception): the minimum of `repeats` runs, or of one if it takes over
    once_above; the first failure ends it."""
    best, out = math.inf, None
    for _ in range(repeats):
        seconds, got = timed(fun, limit)
        if isinstance(got, Exception):
            return seconds, got
        best, out = min(best, seconds), got
        if seconds > once_above:
            break
    return best, out


def core_seconds(run, repeats: int) -> float:
    """The exact core's CPU time on a run (the minimum of repeats; it is milliseconds): what budgets scale with,
    counted as they are (see `timed`).  The minimum leaves out a first call's compiling or cache loading: a cold
    cache is no slowness."""
    best = math.inf
    for _ in range(max(repeats, 3)):
        t0 = time.process_time()
        run()
        best = min(best, time.process_time() - t0)
    return best


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
    once_above = repeat_below(cfg)
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
        limit = run_budget(cfg, core_seconds(lambda: run_method("core", 0.0, system, r, start, t_end, t_window),
                                             repeats))
        for im, method in enumerate(methods):
            for iset, setting in enumerate(ladders[method][1]):
                setting_value[im, iset] = setting
                run_method(method, setting, system, r, start, min(t_end, 2 * math.pi), 0.5)  # warm-up
                best, out = timed_repeats(lambda: run_method(method, setting, system, r, start, t_end, t_window),
                                          budget(cfg) if method == "core" else limit, repeats, once_above)
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
    ds = with_integer_counts(ds)
    ds["predictability_horizon"] = ("case", [horizon[c] for c in cases], {
        "units": "1", "long_name": "dimensionless time (Omega t) after which round-off-perturbed runs differ by 1e-3"})
    ds.attrs.update(reference="the exact event-driven core (impact.engine.paper)", k_impacts=K_IMPACTS,
                    wall_time=f"minimum of {repeats} repeats after a warm-up (one for a run over "
                              f"{once_above:g} s)", repeats=repeats, budget_seconds=budget(cfg),
                    budget_over_core=str(cfg.get("budget_over_core", DEFAULT_BUDGET_OVER_CORE)))
    return ds


def stability_runs(cfg: dict, families=None, log=None) -> pd.DataFrame:
    """Every method of `families` (default: all) on every extreme case, one row per run, not yet judged."""
    periods = float(cfg.get("stability_periods", 50))
    t_end = 2 * math.pi * periods
    rows = []
    methods = {m: v for m, v in stability_methods(cfg).items() if families is None or family(m) in families}
    for case, (system, r, start) in extreme_cases(cfg).items():
        limit = run_budget(cfg, core_seconds(lambda: run_method("core", 0.0, system, r, start, t_end, 0.5 * t_end),
                                             3))
        for method, setting in methods.items():
            seconds, out = timed(lambda: run_method(method, setting, system, r, start, t_end, 0.5 * t_end),
                                 budget(cfg) if method == "core" else limit)
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


def stability(cfg: dict, log=None) -> pd.DataFrame:
    """Every method on every extreme case, judged: the stability table in one piece."""
    return stability_table([stability_runs(cfg, log=log)], cfg)
