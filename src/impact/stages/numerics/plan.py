"""The numerics stage's plan: its cases, method ladders, budgets and pieces, from the configuration.
Nothing here runs the engine, so the workflow's start-up reads it without loading numba."""

from __future__ import annotations

import math

from impact.model.kinds import CID, PID
from impact.model.params import System, a_max

K_IMPACTS = 20


# methods that differ only in a setting or a solver option run as one piece of work
FAMILIES = ("core", "ivp", "rk4", "moreau_jean", "penalty")


# The cost rule (the configuration's numerics section states it too): each run costs only what it shows.  A run
# longer than repeat_below is timed once, its timer's noise being far below its time; a shorter one keeps the
# minimum of `repeats`.  A baseline run stops at budget_over_core times the exact core's time on the same run
# (by then it has shown it is that much slower), or at `budget` seconds, whichever comes first; both count the
# process's CPU time, which a loaded machine does not stretch as it does wall time.
DEFAULT_REPEAT_BELOW = 0.1   # s
DEFAULT_BUDGET = 10.0        # s of CPU time per run
DEFAULT_BUDGET_OVER_CORE = 1.0e4


def family(method: str) -> str:
    """The family of a method: ivp for every solve_ivp method, else the method itself."""
    return "ivp" if method.startswith("ivp_") else method


def work_precision_cases(cfg: dict) -> dict:
    """Name -> (system, r, start, natural periods) of the work-precision cases (those named in cfg's
    work_precision_cases, if given)."""
    return _chosen(_all_work_precision_cases(float(cfg.get("periods", 40))), cfg.get("work_precision_cases"),
                   "work_precision_cases")


def _chosen(cases: dict, chosen, key: str) -> dict:
    """The cases named (all when None), in their own order; an unknown name refused naming the key."""
    if chosen is None:
        return cases
    unknown = sorted(set(chosen) - set(cases))
    if unknown:
        raise ValueError(f"numerics.{key}: unknown case(s) {unknown}; allowed: {list(cases)}")
    return {name: case for name, case in cases.items() if name in chosen}


def _all_work_precision_cases(periods: float) -> dict:
    paper = dict(mu=0.01, beta=0.0048, e=0.25)
    return {
        "cid_2eipc": (System.from_gap_ratio(CID, gap_ratio=1.6, **paper), 1.0, "left", periods),
        "cid_irregular": (System.from_gap_ratio(CID, mu=0.01, beta=0.0048, e=0.65, gap_ratio=0.5), 0.97,
                          "centre", periods),
        "pid_tuned": (System.from_gap_ratio(PID, gap_ratio=1.0, rp=1.0, **paper), 1.0, "centre", periods),
        "cid_friction": (System.from_gap_ratio(CID, gap_ratio=1.6, nu=0.05, **paper), 1.0, "left", periods),
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


def budget(cfg: dict) -> float:
    return float(cfg.get("budget", DEFAULT_BUDGET))


def repeat_below(cfg: dict) -> float:
    return float(cfg.get("repeat_below", DEFAULT_REPEAT_BELOW))


def run_budget(cfg: dict, core_seconds: float) -> float:
    """The seconds one baseline run may take on a case whose exact-core run takes core_seconds."""
    factor = cfg.get("budget_over_core", DEFAULT_BUDGET_OVER_CORE)
    return budget(cfg) if factor is None else min(budget(cfg), float(factor) * core_seconds)


def work_precision_pieces(cfg: dict) -> list[tuple[str, str]]:
    """(case, family) of every piece of work of the study."""
    families = {family(m) for m in method_ladders(cfg)}
    return [(case, fam) for case in work_precision_cases(cfg) for fam in FAMILIES if fam in families]


def extreme_cases(cfg: dict) -> dict:
    """Name -> (system, r, start) of the stiff and extreme cases (those named in cfg's stability_cases, if
    given)."""
    return _chosen(_all_extreme_cases(), cfg.get("stability_cases"), "stability_cases")


def _all_extreme_cases() -> dict:
    base = dict(mu=0.01, beta=0.0048, e=0.25)

    def cid(**kw):
        g = kw.pop("gap_ratio", 1.0)
        return System.from_gap_ratio(CID, gap_ratio=g, **{**base, **kw})

    amax = a_max(0.0048, 0.096)
    bare = 0.096 / math.hypot(1 - 0.95 ** 2, 2 * 0.0048 * 0.95)  # bare amplitude at r = 0.95
    return {
        "e=0": (cid(e=0.0), 1.0, "centre"),
        "e=1e-3": (cid(e=1e-3), 1.0, "centre"),
        "e=0.999": (cid(e=0.999), 1.0, "centre"),
        "e=1": (cid(e=1.0), 1.0, "centre"),
        "g=1e-3": (cid(gap_ratio=1e-3), 1.0, "centre"),
        "g=1e-6": (cid(gap_ratio=1e-6), 1.0, "centre"),
        "beta=0": (System(CID, mu=0.01, beta=0.0, e=0.25, gap=1.0), 0.97, "centre"),
        "beta=1e-5": (System(CID, mu=0.01, beta=1e-5, e=0.25, gap=1.0), 1.0, "centre"),
        "mu=1e-4": (cid(mu=1e-4), 1.0, "centre"),
        "mu=0.5": (cid(mu=0.5), 1.0, "centre"),
        "stiff pendulum r'=100": (System.from_gap_ratio(PID, gap_ratio=1e-3, rp=100.0, **base), 1.0, "left"),
        # the damper mass rests against the left wall and the structure's steady swing
        # just reaches the right wall: grazing contact
        "grazing": (System(CID, mu=1e-6, beta=0.0048, e=0.5, gap=2 * bare * (1 + 1e-9)), 0.95, "centre"),
        "friction nu=5": (cid(nu=5.0, gap_ratio=1.6), 1.0, "left"),
    } | ({} if amax else {})


def stability_methods(cfg: dict) -> dict:
    """One mid-range setting per method for the stability table."""
    return {"core": 0.0, "ivp_RK45": 1e-8, "ivp_DOP853": 1e-8, "ivp_Radau": 1e-8, "ivp_LSODA": 1e-8,
            "rk4": 200, "moreau_jean": 200, "penalty": 1e5} | cfg.get("stability_settings", {})


def stability_families(cfg: dict) -> list[str]:
    """The families of the stability table's methods, one piece of work each."""
    present = {family(m) for m in stability_methods(cfg)}
    return [fam for fam in FAMILIES if fam in present]

class Timeout(Exception):
    pass
