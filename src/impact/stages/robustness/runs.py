"""The robustness stage's runs: each design's X_m and stroke along its variations, on the exact engine
(:func:`impact.engine.run.simulate`), and its dataset."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import xarray as xr

from impact.engine.run import simulate
from impact.model.building import Building
from impact.model.kinds import KINDS
from impact.model.params import Protocol, System, a_max
from impact.model.scene import Damper, Harmonic, Scene, paper_scene_from_system
from impact.stages.robustness.designs import (
    MEASURES,
    VARIATIONS,
    Conditions,
    Design,
    applicable,
    bare_amplitude,
    has_paper_form,
    random_starts,
    staggered_starts,
)


def design_scene(design: Design, r: float, protocol: Protocol, conditions: Conditions = Conditions(),
                 unit_starts=None) -> Scene:
    """One run: the design under ``conditions``, forced at r times the structure's own frequency.

    unit_starts: each unit's initial place between its walls (default: all at the design's start)."""
    w = conditions.frequency
    building = Building.explicit([1.0], [w * w], zeta=design.beta)
    parts = KINDS[design.kind]
    tuning = design.tuning / w if parts.spring else 0.0
    if parts.walls:
        damper = Damper(design.kind, mass=design.mu, gap=design.gap, e=design.e, tuning=tuning,
                        damping=design.damping, units=design.units)
    else:
        damper = Damper(design.kind, mass=design.mu, tuning=tuning, damping=design.damping)
    period = 2.0 * math.pi / w
    return Scene(building, (damper,), Harmonic(conditions.scale * design.force_ratio, r * w, 0.0),
                 duration=protocol.periods * period, window=protocol.average_from * period,
                 start=design.start if parts.walls else "centre",
                 unit_starts=None if unit_starts is None else tuple(unit_starts))


def paper_system(design: Design, conditions: Conditions = Conditions()) -> System:
    """The undamped CID or PID under ``conditions`` as the paper's System, by exact similarity.

    In the drifted structure's own time (t' = (1 + delta) t) and the same lengths, the motion is the design's
    with the force F s / (1 + delta)^2, the same clearance d and the pendulum's frequency r' / (1 + delta).
    """
    if not KINDS[design.kind].paper or design.damping != 0.0:
        raise ValueError("the paper's system is an undamped CID or PID: no TMD and no pendulum damping")
    w = conditions.frequency
    return System(design.kind, mu=design.mu, beta=design.beta, e=design.e, gap=design.gap,
                  rp=design.tuning / w if KINDS[design.kind].spring else 0.0,
                  force_ratio=conditions.scale * design.force_ratio / (w * w))


def peak_response(design: Design, r_grid, protocol: Protocol, conditions: Conditions = Conditions()) -> dict:
    """X_m over the frequency grid and its frequency; for a design without the paper's form also the damper's
    stroke (the largest over the grid, and at X_m).  A design with the paper's form (:func:`has_paper_form`) is
    described as the paper's system in the drifted structure's own time (:func:`paper_system`), and asks for
    the amplitude alone: the engine runs it on its paper loop, five to ten times faster, which measures no
    stroke; :func:`scene_peak_response` measures it."""
    r_grid = np.asarray(r_grid, dtype=float)
    if has_paper_form(design):
        system = paper_system(design, conditions)
        start = replace(protocol, start=design.start)
        ratios = np.array([simulate(paper_scene_from_system(system, float(r), start)).amplitude / system.a_max
                           for r in r_grid])
        i = int(np.argmax(ratios))
        return {"X_m": float(ratios[i]), "r_at_max": float(r_grid[i])}
    return scene_peak_response(design, r_grid, protocol, conditions)


def scene_peak_response(design: Design, r_grid, protocol: Protocol, conditions: Conditions = Conditions(),
                        unit_starts=None) -> dict:
    """:func:`peak_response` on the scene core, for any damper, with its stroke."""
    amps, strokes = [], []
    for r in np.asarray(r_grid, dtype=float):
        result = simulate(design_scene(design, float(r), protocol, conditions, unit_starts),
                          measures=("amplitude", "strokes"))
        amps.append(result.amplitude)
        strokes.append(float(np.max(result.peak_strokes)))
    amps, strokes = np.array(amps), np.array(strokes)
    i = int(np.argmax(amps))
    return {"X_m": float(amps[i] / bare_amplitude(design, conditions)), "r_at_max": float(r_grid[i]),
            "stroke_at_max": float(strokes[i]), "stroke_max": float(np.max(strokes))}


def sensitivity(design: Design, r_grid, protocol: Protocol, *, scales=(), drifts=(), dampings=(),
                restitutions=()) -> dict:
    """X_m (and stroke) along each requested variation; each list is swept alone, the rest as designed."""
    out = {}
    out["scale"] = [peak_response(design, r_grid, protocol, Conditions(scale=s)) for s in scales]
    out["drift"] = [peak_response(design, r_grid, protocol, Conditions(drift=d)) for d in drifts]
    out["damping"] = [peak_response(replace(design, damping=z), r_grid, protocol) for z in dampings]
    out["e"] = [peak_response(replace(design, e=e), r_grid, protocol) for e in restitutions]
    return out


def capped_tmd_damping(design: Design, r_grid, protocol: Protocol, stroke_cap: float, *, tol: float = 1e-3,
                       beta_t_max: float = 0.9, at: dict | None = None) -> tuple[float, dict]:
    """The smallest beta_t (from the design's up) whose largest stroke over the grid is within ``stroke_cap``.

    Bisection on beta_t: a TMD's stroke falls as its damping rises.  ``at``: the design's own peak response,
    if already run.  Returns (beta_t, its peak response).
    """
    if KINDS[design.kind].walls:
        raise ValueError("only a damper without walls (a TMD) has its stroke capped by raising its damping")
    lo, hi = design.damping, beta_t_max
    at = at or peak_response(design, r_grid, protocol)
    if at["stroke_max"] <= stroke_cap:
        return lo, at
    top = peak_response(replace(design, damping=hi), r_grid, protocol)
    if top["stroke_max"] > stroke_cap:
        raise ValueError(f"no beta_t up to {beta_t_max} keeps the TMD's stroke within {stroke_cap}")
    while hi - lo > tol * hi:
        mid = 0.5 * (lo + hi)
        res = peak_response(replace(design, damping=mid), r_grid, protocol)
        lo, hi, top = (mid, hi, top) if res["stroke_max"] > stroke_cap else (lo, mid, res)
    return hi, top


def design_dataset(design: Design, grids: dict, r_grid, protocol: Protocol, stroke_cap: float | None = None):
    """X_m, its frequency and the stroke at the design point and along each applicable variation.

    grids: variation name -> values (scale, drift, damping, e); the ones that do not apply are left out.
    stroke_cap (TMD only): also the smallest beta_t that keeps its stroke within it, and X_m then.
    """

    wanted = {name: np.asarray(grids[name], dtype=float) for name in applicable(design.kind) if name in grids}
    sweeps = sensitivity(design, r_grid, protocol, scales=wanted.get("scale", ()), drifts=wanted.get("drift", ()),
                         dampings=wanted.get("damping", ()), restitutions=wanted.get("e", ()))
    # the stroke needs the scene loop, so the design point always runs there (Table 1, row 5); a design with
    # the paper's form takes its X_m from the paper loop, as along its variations
    on_scene = scene_peak_response(design, r_grid, protocol)
    design_point = {**on_scene, **peak_response(design, r_grid, protocol)} if has_paper_form(design) else on_scene
    data = {f"{m}_design": ((), design_point[m], {"long_name": f"{text}, at the design point", "units": u})
            for m, (text, u) in MEASURES.items()}
    coords = {}
    for name, values in wanted.items():
        text, units = VARIATIONS[name]
        coords[name] = (name, values, {"long_name": text, "units": units})
        for m, (mtext, u) in MEASURES.items():
            if all(m in run for run in sweeps[name]):
                data[f"{m}_vs_{name}"] = (name, [run[m] for run in sweeps[name]], {"long_name": mtext, "units": u})
    if stroke_cap is not None:
        beta_t, capped = capped_tmd_damping(design, r_grid, protocol, stroke_cap, at=on_scene)
        data["stroke_cap"] = ((), stroke_cap, {"long_name": "the stroke the TMD is held to: half a CID's gap",
                                               "units": "1"})
        data["damping_capped"] = ((), beta_t, {"long_name": "smallest TMD damping ratio whose stroke fits the cap",
                                               "units": "1"})
        data["X_m_capped"] = ((), capped["X_m"], {"long_name": "X_m of the TMD with its stroke capped",
                                                  "units": "1"})
    ds = xr.Dataset(data, coords=coords)
    if KINDS[design.kind].walls and grids.get("units"):
        add_multi_unit(ds, design, grids["units"], r_grid, protocol, grids["members"], grids["seed"],
                       single=on_scene)
    ds.attrs.update({"title": f"Table 1 in numbers: design {design.kind}", "kind": design.kind,
                     "design": str(design.__dict__),
                     "a_max": a_max(design.beta, design.force_ratio), "periods": protocol.periods,
                     "average_from": protocol.average_from, "initial_condition": f"structure at rest, damper mass "
                     f"{'at start ' + design.start if KINDS[design.kind].walls else 'centred'}",
                     "length_unit": "the paper's model unit (F0/K = force_ratio at the design force)"})
    return ds


def multi_unit(design: Design, units, r_grid, protocol: Protocol, members: int, seed: int,
               single: dict | None = None) -> dict:
    """X_m of the design split into n units of the same total mass and gap, for each n in ``units``.

    'symmetric': every unit at the design's start (identical units that start together move as one);
    'staggered': the units spread evenly from wall to wall; 'ensemble': ``members`` seeded random starts.
    ``single``: the one unit's scene response at the design's start, if already run (both n = 1 rows).
    """
    if not KINDS[design.kind].walls:
        raise ValueError("the multi-unit rows are the impact dampers' (the kinds with walls)")
    out = {"symmetric": [], "staggered": [], "ensemble": []}
    for n in units:
        split = replace(design, units=int(n))
        if n == 1:  # one unit: the design itself, wherever 'staggered' would spread it
            single = single or scene_peak_response(split, r_grid, protocol)
            out["symmetric"].append(single["X_m"])
            out["staggered"].append(single["X_m"])
        else:
            out["symmetric"].append(scene_peak_response(split, r_grid, protocol)["X_m"])
            out["staggered"].append(scene_peak_response(split, r_grid, protocol,
                                                        unit_starts=staggered_starts(n, design.gap))["X_m"])
        out["ensemble"].append([scene_peak_response(split, r_grid, protocol,
                                                    unit_starts=random_starts(n, design.gap, seed, m))["X_m"]
                                for m in range(members)])
    return out


def add_multi_unit(ds, design: Design, units, r_grid, protocol: Protocol, members: int, seed: int,
                   single: dict | None = None) -> None:
    """The multi-unit rows as variables over ``units`` (and ``member`` for the ensemble)."""
    rows = multi_unit(design, units, r_grid, protocol, members, seed, single)
    ds.coords["units"] = ("units", np.asarray(units, dtype=np.int64), {
        "long_name": "number of identical units (same total mass and gap)", "units": "1"})
    ds.coords["member"] = ("member", np.arange(members), {"long_name": "ensemble member (seeded starts)",
                                                           "units": "1"})
    ds["X_m_units_symmetric"] = ("units", rows["symmetric"], {
        "long_name": "X_m with every unit at the design's start", "units": "1"})
    ds["X_m_units_staggered"] = ("units", rows["staggered"], {
        "long_name": "X_m with the units spread evenly from wall to wall", "units": "1"})
    ds["X_m_units_ensemble"] = (("units", "member"), rows["ensemble"], {
        "long_name": "X_m with the units at seeded random places between their walls", "units": "1"})
    ds.attrs["ensemble_seed"] = seed
