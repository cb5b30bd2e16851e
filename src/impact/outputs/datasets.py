"""Self-describing sweep datasets (CF conventions) and atomic netCDF writes.

A curve of a figure is one damper configuration swept over gap ratios and
frequencies, for one or more initial placements of the damper mass.  Only
what the scene uses is stored: no pendulum fields for a CID, no friction
fields when nu = 0.
"""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from impact.model.kinds import KINDS
from impact.model.params import Protocol, System
from impact.outputs.files import flag
from impact.outputs.labels import EVENT_CAP_MEANINGS
from impact.outputs.provenance import attributes

IPC_FLAG_VALUES = np.array([-1, 0, 1, 2, 3], dtype=np.int8)
IPC_FLAG_MEANINGS = "undefined less_than_1_ipc one_ipc two_ipc more_than_2_ipc"
# The paper's lengths are in an arbitrary model unit (F0/K = force_ratio of them): a pure number to UDUNITS.
# The datasets say so in their global attribute length_unit.
LENGTH_UNIT = "1"
LENGTH_NOTE = "lengths are in the paper's model unit, in which the static deflection F0/K equals force_ratio"

_PER_RUN = {
    # name: (source, dtype, units, long_name)
    "amplitude": ("amplitude", "f8", LENGTH_UNIT, "steady-state amplitude of the structure, sqrt(2) * RMS of x over the window"),
    "amplitude_ratio": ("amplitude_ratio", "f8", "1", "amplitude over A_max, the bare structure's resonant amplitude"),
    "aipc": ("aipc", "f8", "1", "average impacts per excitation cycle in the window"),
    "impacts": ("impacts", "i4", "1", "impacts over the whole run"),
    "sticking_episodes": ("sticking_episodes", "i4", "1", "episodes of the damper mass resting against a wall"),
    "grazing_events": ("grazing_events", "i4", "1", "wall touches resolved at the contact tolerance"),
    "max_penetration": ("max_penetration", "f8", LENGTH_UNIT, "largest overshoot beyond a wall at a located impact"),
    "energy_residual": ("energy_residual", "f8", "1",
                        "energy-balance residual over the largest of the force's work, the losses and the stored energy"),
    "event_cap_reached": ("event_cap_reached", "i1", None, "the run stopped at the cap on events per period"),
}
#: the flags' meanings (values 0 and 1): a flag has these instead of a unit
_FLAGS = {"event_cap_reached": EVENT_CAP_MEANINGS,
          "two_ipc_at_max": ("not_two_ipc", "two_ipc")}


def _run_value(run, name):
    if name in ("amplitude", "amplitude_ratio", "aipc"):
        return getattr(run, name)
    return run.diagnostics[name]


def curve_dataset(base: System, gap_ratios, starts, results, protocol: Protocol, curve: dict | None = None,
                  config: dict | None = None, sweep_mode: str = "from_rest") -> xr.Dataset:
    """Dataset of one curve.

    results[i_start][i_gap] is the SweepResult of that start and gap ratio; all
    share the same frequency grid.
    """
    starts = list(starts)
    gap_ratios = np.asarray(gap_ratios, dtype=float)
    r = np.asarray(results[0][0].r, dtype=float)
    shape = (len(starts), len(gap_ratios), len(r))
    data = {}
    for name, (_, dtype, units, long_name) in _PER_RUN.items():
        arr = np.empty(shape, dtype=dtype)
        for i, row in enumerate(results):
            for j, sw in enumerate(row):
                arr[i, j, :] = [_run_value(run, name) for run in sw.runs]
        attrs = flag(long_name, *_FLAGS[name]) if name in _FLAGS else {"units": units, "long_name": long_name}
        data[name] = (("start", "gap_ratio", "freq_ratio"), arr, attrs)
    ipc = np.array([[[run.ipc_class for run in sw.runs] for sw in row] for row in results], dtype=np.int8)
    data["ipc_class"] = (("start", "gap_ratio", "freq_ratio"), ipc, {
        "long_name": "impacts-per-cycle class of the paper", "flag_values": IPC_FLAG_VALUES,
        "flag_meanings": IPC_FLAG_MEANINGS})
    ds = xr.Dataset(data, coords={
        "start": ("start", np.array(starts, dtype=object), {"long_name": "initial place of the damper mass (structure at rest)"}),
        "gap_ratio": ("gap_ratio", gap_ratios, {"units": "1", "long_name": "gap ratio g = d / A_max"}),
        "freq_ratio": ("freq_ratio", r, {"units": "1", "long_name": "frequency ratio r = Omega / omega"}),
    })
    ds = ds.assign_coords(gap=("gap_ratio", gap_ratios * base.a_max, {"units": LENGTH_UNIT, "long_name": "total clearance d"}))
    add_reductions(ds)
    ds.attrs.update(_attributes(base, protocol, curve, config, sweep_mode))
    return ds


def add_reductions(ds: xr.Dataset) -> None:
    """The paper's reductions of a sweep: x_max, X_m and the IPC class at the maximum."""
    amp = ds["amplitude"]
    ds["x_max"] = amp.max("freq_ratio", skipna=False).assign_attrs(
        units=LENGTH_UNIT, long_name="largest amplitude of the frequency sweep")
    ds["X_m"] = ds["amplitude_ratio"].max("freq_ratio", skipna=False).assign_attrs(
        units="1", long_name="amplitude ratio X_m = x_max / A_max")
    imax = amp.fillna(-np.inf).argmax("freq_ratio")
    ds["r_at_max"] = ds["freq_ratio"].isel(freq_ratio=imax).drop_vars("freq_ratio").assign_attrs(
        units="1", long_name="frequency ratio of the largest amplitude")
    ipc_at = ds["ipc_class"].isel(freq_ratio=imax).drop_vars("freq_ratio")
    ds["ipc_class_at_max"] = ipc_at.astype(np.int8).assign_attrs(
        long_name="IPC class at the largest amplitude", flag_values=IPC_FLAG_VALUES, flag_meanings=IPC_FLAG_MEANINGS)
    # a fresh variable: the comparison would keep ipc_at's flag attributes, whose meanings are the IPC classes'
    ds["two_ipc_at_max"] = xr.DataArray((ipc_at == 2).values.astype(np.int8), dims=ipc_at.dims,
                                        attrs=flag("the motion at the largest amplitude is 2 IPC", *_FLAGS["two_ipc_at_max"]))


def _attributes(base: System, protocol: Protocol, curve, config, sweep_mode) -> dict:
    params = {"damper": base.kind, "mu": base.mu, "beta": base.beta, "e": base.e,
              "force_ratio": base.force_ratio, "phase": base.phase, "a_max": base.a_max}
    if KINDS[base.kind].spring:
        params["rp"] = base.rp
    if base.nu > 0:
        params.update(nu=base.nu, frequency_hz=base.frequency_hz, unit_m=base.unit_m,
                      friction_accel=base.friction_accel)
    attrs = {
        "length_unit": LENGTH_NOTE,
        "title": f"Frequency sweeps of the {base.kind.upper()} over gap ratios (Chua et al. parametric study)",
        "institution": "impact-dampers study",
        "references": "Chua, Pacheco, Fujino, Ito: classical and pendulum impact dampers for civil structures",
        "initial_condition": ("structure at rest (x = x' = 0); damper mass at rest at the place named by the "
                              "'start' coordinate: centre (s = 0) or left/right wall (s = -/+ d/2)"
                              + ("" if sweep_mode == "from_rest" else
                                 "; at the first frequency of the continuation only, later ones start from "
                                 "the final state of the previous frequency")),
        "protocol": json.dumps({"periods": protocol.periods, "average_from": protocol.average_from,
                                "amplitude": "sqrt(2)*RMS of x over the window, exact integral",
                                "sweep_mode": sweep_mode}),
        "sweep_mode": sweep_mode,
        "parameters": json.dumps(params),
    }
    attrs.update({f"param_{k}": v for k, v in params.items()})
    attrs.update(attributes())
    if curve:
        attrs["curve"] = json.dumps(curve, sort_keys=True)
    if config is not None:
        attrs["config"] = json.dumps(config, sort_keys=True)
    return attrs


def optimum(ds, start: str | None, reading: str = "X_m") -> tuple[float, float]:
    """(g, X_m) at the lowest X_m of one start's curve (the paper's 'optimum gap ratio').

    reading: the variable read as X_m (X_m_refined, X_m_hybrid; X_m_closed_form has no start: None).
    """
    xm = (ds[reading] if start is None else ds[reading].sel(start=start)).values
    if not np.any(np.isfinite(xm)):
        return math.nan, math.nan
    i = int(np.nanargmin(xm))
    return float(ds["gap_ratio"].values[i]), float(xm[i])


def two_ipc_range(ds, start: str) -> tuple[float, float]:
    """Smallest and largest g whose motion at x_max is 2 IPC (NaN if none)."""
    flag = ds["two_ipc_at_max"].sel(start=start).values.astype(bool)
    g = ds["gap_ratio"].values[flag]
    return (float(g.min()), float(g.max())) if g.size else (math.nan, math.nan)


def time_history_dataset(t, roof, stroke, half_gap: float, impact_time, impact_impulse, *, length_unit: str,
                         impulse_unit: str, title: str, kind: str, roof_bare=None, **attrs) -> xr.Dataset:
    """One run in time: the structure's (roof's) displacement, with and without the damper, the damper mass
    relative to its floor between its walls, and each impact's time and momentum.  What a run looks like
    (impact run --plot, impact quake --plot, the loads stage's case in time), drawn by
    :func:`impact.outputs.plotting.plot_time_history`."""
    data = {
        "roof_damped": ("t", np.asarray(roof), {"long_name": f"roof displacement with the {kind.upper()}",
                                                 "units": length_unit}),
        "stroke": ("t", np.asarray(stroke), {"long_name": "damper mass relative to its floor", "units": length_unit}),
        "impact_time": ("impact", np.asarray(impact_time), {"long_name": "time of each impact", "units": "s"}),
        "impact_impulse": ("impact", np.abs(np.asarray(impact_impulse)),
                           {"long_name": "momentum exchanged in the impact", "units": impulse_unit}),
        "half_gap": ((), half_gap, {"long_name": "half the clearance: where the walls are", "units": length_unit}),
    }
    if roof_bare is not None:
        data["roof_bare"] = ("t", np.asarray(roof_bare), {"long_name": "roof displacement, bare building",
                                                          "units": length_unit})
    # "t", not "time": CF reserves a coordinate named time for dates ("seconds since ...")
    ds = xr.Dataset(data, coords={"t": ("t", np.asarray(t), {"long_name": "time since the start", "units": "s"})})
    ds.attrs.update(title=title, damper=kind, **attrs)
    return ds
