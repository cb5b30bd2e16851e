"""Coexisting steady states of the CID: continuation sweeps and the initial-condition envelope.

The paper's protocol restarts every frequency from rest; a shaker-table sweep
carries its state from one frequency to the next (continuation), and a real
damper may start anywhere.  For a curve we run both continuation directions
and an ensemble of starting states, and report the envelope of X_m: the worst
case a design engineer must expect, not one lucky start.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from impact.engine.run import sweep
from impact.model.params import Protocol, System, curve_id
from impact.model.scene import Contact, State
from impact.outputs.datasets import LENGTH_NOTE, LENGTH_UNIT
from impact.stages.sweeps import curve_system, freq_grid, gap_grid

#: amplitude and AIPC tolerances that tell two attractors apart (window transients stay below)
AMPLITUDE_RTOL = 1e-2
AIPC_ATOL = 0.05


def ensemble_members(n: int, seed: int) -> pd.DataFrame:
    """Starting states, as fractions so they apply to every gap.

    Members 0-2 are the protocol's starts at rest (centre, left, right wall);
    the others draw, from a seeded generator, the damper mass's place across
    the clearance (s0 / (d/2) in [-1, 1]), its velocity relative to the
    structure (in units of A_max * omega) and the structure's displacement
    (in units of A_max, at rest).
    """
    if n < 3:
        raise ValueError("an ensemble needs at least the three protocol starts (members >= 3)")
    rng = np.random.default_rng(seed)
    rest = pd.DataFrame({"place": [0.0, -1.0, 1.0], "velocity": [0.0] * 3, "structure": [0.0] * 3})
    drawn = pd.DataFrame({"place": rng.uniform(-1.0, 1.0, n - 3), "velocity": rng.uniform(-1.0, 1.0, n - 3),
                          "structure": rng.uniform(-1.0, 1.0, n - 3)})
    return pd.concat([rest, drawn], ignore_index=True)


def member_state(system: System, member) -> State:
    """Where one member starts for this system: at rest on a wall, or free."""
    half = 0.5 * system.gap
    if member["velocity"] == 0.0 and abs(member["place"]) == 1.0 and system.gap > 0:
        side = int(member["place"])
        return State.paper((0.0, 0.0, side * half, 0.0), Contact("held", side))
    x0 = member["structure"] * system.a_max
    return State.paper((x0, 0.0, x0 + member["place"] * half, member["velocity"] * system.a_max))


def count_attractors(amplitude: np.ndarray, aipc: np.ndarray) -> int:
    """Distinct (amplitude, AIPC) pairs among members, within the tolerances."""
    seen = []
    for a, n in zip(amplitude, aipc):
        if not (math.isfinite(a) and math.isfinite(n)):
            continue
        if not any(abs(a - b) <= AMPLITUDE_RTOL * max(abs(a), abs(b)) and abs(n - m) <= AIPC_ATOL for b, m in seen):
            seen.append((a, n))
    return len(seen)


def run_ensemble(cfg: dict, spec: dict, members: pd.DataFrame, protocol: Protocol) -> xr.Dataset:
    gaps = gap_grid(cfg)
    r = freq_grid(cfg)
    amp = np.empty((len(members), len(gaps), len(r)))
    aipc = np.empty_like(amp)
    for j, g in enumerate(gaps):
        system = curve_system(cfg, spec, float(g))
        for i, member in members.iterrows():
            result = sweep(system, r, protocol, initial=member_state(system, member))
            amp[i, j] = result.column("amplitude")
            aipc[i, j] = result.column("aipc")
    return ensemble_dataset(spec, members, gaps, r, amp, aipc, curve_system(cfg, spec, 1.0).a_max)


def ensemble_dataset(spec, members, gaps, r, amp, aipc, a_max) -> xr.Dataset:
    dims = ("member", "gap_ratio", "freq_ratio")
    ds = xr.Dataset(
        {"amplitude": (dims, amp, {"units": LENGTH_UNIT, "long_name": "sqrt(2)*RMS amplitude of x"}),
         "aipc": (dims, aipc, {"units": "1", "long_name": "average impacts per cycle"})},
        coords={"member": ("member", np.arange(len(members)), {"units": "1", "long_name": "ensemble member"}),
                "gap_ratio": ("gap_ratio", gaps, {"units": "1", "long_name": "gap ratio g = d / A_max"}),
                "freq_ratio": ("freq_ratio", r, {"units": "1", "long_name": "frequency ratio r"}),
                "start_place": ("member", members["place"].to_numpy(), {
                    "units": "1", "long_name": "damper mass's initial place s0 / (d/2)"}),
                "start_velocity": ("member", members["velocity"].to_numpy(), {
                    "units": "1", "long_name": "damper mass's initial velocity relative to the structure / (A_max omega)"}),
                "start_structure": ("member", members["structure"].to_numpy(), {
                    "units": "1", "long_name": "structure's initial displacement / A_max (at rest)"})})
    xm = amp.max(axis=2) / a_max
    ds["X_m"] = (("member", "gap_ratio"), xm, {"units": "1", "long_name": "amplitude ratio X_m of each member"})
    for stat, fun in (("min", np.nanmin), ("median", np.nanmedian), ("max", np.nanmax)):
        ds[f"X_m_{stat}"] = ("gap_ratio", fun(xm, axis=0), {"units": "1", "long_name": f"{stat} of X_m over the ensemble"})
    counts = np.array([[count_attractors(amp[:, j, k], aipc[:, j, k]) for k in range(len(r))]
                       for j in range(len(gaps))])
    ds["attractors"] = (("gap_ratio", "freq_ratio"), counts.astype(np.int16), {
        "units": "1", "long_name": "distinct steady states met (by amplitude and AIPC)"})
    ds["attractors_max"] = ("gap_ratio", counts.max(axis=1).astype(np.int16), {
        "units": "1", "long_name": "most distinct steady states met at one frequency"})
    ds.attrs.update(curve=str(curve_id(spec)), a_max=a_max, length_unit=LENGTH_NOTE,
                    attractor_tolerances=f"amplitude rel {AMPLITUDE_RTOL}, AIPC abs {AIPC_ATOL}")
    return ds
