"""The model side of the cross-validation: Eq. (4) of the paper, sampled into records.

Eq. (4) -- a linear pendulum, instantaneous Newton impacts -- is a Scene of the paper's system (model units
M = 1, omega = 1, lengths in mm) that the engine's entry point sends to its paper loop, whose dense output
samples it at the sensor's rate exactly; the samples become records of the experiment data format (``synthetic: true``),
so that it goes through the same analysis code as the rig's records (:mod:`.comparison`).  The
bare structure (mu = 0) is its exact closed form.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from impact.engine.run import simulate
from impact.model.kinds import PID
from impact.model.params import Protocol, System
from impact.model.scene import Scene, State, paper_scene_from_system
from impact.outputs.measurements import Measurement, make_measurement
from impact.rig import simulator as R
from impact.rig.config import validation_config
from impact.stages.validation.grid import Case, wall_e

MODEL_SOURCE = ("model: Eq. (4) of the paper (linear pendulum, instantaneous impacts) simulated by the "
                "production exact event-driven kernel impact.engine.paper_loop.run; synthetic")


def model_system(cfg: dict, case: Case) -> System:
    """Eq. (4) in model units (M = 1, omega = 1, lengths in mm) for a case."""
    return System(kind=PID, mu=case.mu, beta=float(cfg["structure"]["beta"]), e=wall_e(cfg, case.wall),
                  gap=case.gap_mm, rp=case.rp, force_ratio=float(cfg["excitation"]["force_ratio_mm"]),
                  phase=float(cfg["excitation"].get("phase", 0.0)),
                  frequency_hz=float(cfg["structure"]["frequency_hz"]), unit_m=1e-3)


@dataclass
class ModelRun:
    t_s: np.ndarray
    x_mm: np.ndarray
    s_mm: np.ndarray
    impact_times_s: np.ndarray
    capped: bool


def _run_model(cfg: dict, case: Case, r: float, ts_s: np.ndarray, *, forced: bool, x0_mm: float = 0.0) -> ModelRun:
    """The model sampled at the times ts_s (s): forced from rest at ratio r, or released from x0 (mm) with the
    pendulum hanging at rest and no force.  A Scene of the paper's system through the engine's entry point, whose
    paper loop gives the state at the samples exactly (its dense output)."""
    omega = 2.0 * math.pi * float(cfg["structure"]["frequency_hz"])
    tm = np.ascontiguousarray(ts_s * omega)
    res = simulate(_model_scene(cfg, case, r, float(tm[-1]), forced=forced, x0_mm=x0_mm), ("samples", "records"),
                   record=MAX_IMPACTS, times=tm)
    q = res.samples["q"]
    return ModelRun(ts_s, q[:, 0], q[:, 1] - q[:, 0], res.records["t"] / omega,
                    res.diagnostics["event_cap_reached"])


#: the impact times a model run keeps
MAX_IMPACTS = 200_000


def _model_scene(cfg: dict, case: Case, r: float, t_end: float, *, forced: bool, x0_mm: float) -> Scene:
    """Eq. (4) as a Scene up to t_end (model units): from rest under the force, or from x0 without it."""
    system = model_system(cfg, case)
    initial = None
    if not forced:
        system = dataclasses.replace(system, force_ratio=0.0)
        initial = State.paper((x0_mm, 0.0, x0_mm, 0.0))
    return paper_scene_from_system(system, r, Protocol(periods=t_end / (2.0 * math.pi), average_from=0.0),
                                   initial=initial)


def _model_header(cfg: dict, case: Case | None, kind: str, notes: str) -> dict:
    fs = float(cfg["sensor"]["sample_rate_hz"])
    hdr: dict[str, Any] = {"format_version": 1, "kind": kind, "synthetic": True, "sample_rate_hz": fs,
                           "units": "mm", "damper": "none" if case is None else PID,
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


def model_forced_point(cfg: dict, case: Case, r: float) -> tuple[Measurement, ModelRun]:
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
    return make_measurement(hdr, {"t_s": ts, "x": run.x_mm, "s": run.s_mm}), run


def model_free_decay(cfg: dict, case: Case, x0_mm: float, duration_s: float) -> tuple[Measurement, ModelRun]:
    """The model's ``free_decay`` record: released from x0 with the pendulum hanging at rest."""
    fs = float(cfg["sensor"]["sample_rate_hz"])
    ts = np.arange(int(math.floor(duration_s * fs)) + 1) / fs
    run = _run_model(cfg, case, 1.0, ts, forced=False, x0_mm=x0_mm)
    if run.capped:
        raise RuntimeError(f"model free decay hit the event cap at {case.id} x0={x0_mm}")
    hdr = _model_header(cfg, case, "free_decay", "released from rest, pendulum hanging")
    hdr["x0_mm"] = float(x0_mm)
    return make_measurement(hdr, {"t_s": ts, "x": run.x_mm, "s": run.s_mm}), run


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


def model_bare_forced_point(cfg: dict, r: float, settle_periods: float, record_periods: float) -> Measurement:
    """Bare structure, exact closed form, sampled over the recording window."""
    ts = _window_times(cfg, settle_periods + record_periods, settle_periods)
    hdr = _model_header(cfg, None, "forced_sweep_point",
                        f"bare structure, exact SDOF from rest, window {settle_periods:g} ... "
                        f"{settle_periods + record_periods:g} periods")
    hdr["source"] = "model: Eq. (4) with mu = 0 (linear SDOF), exact closed form; synthetic"
    hdr["r"] = float(r)
    hdr["forcing_hz"] = float(r) * float(cfg["structure"]["frequency_hz"])
    return make_measurement(hdr, {"t_s": ts, "x": sdof_response(ts, cfg, r)})


def model_bare_free_decay(cfg: dict, x0_mm: float, duration_s: float) -> Measurement:
    fs = float(cfg["sensor"]["sample_rate_hz"])
    ts = np.arange(int(math.floor(duration_s * fs)) + 1) / fs
    hdr = _model_header(cfg, None, "free_decay", "bare structure, exact SDOF free decay")
    hdr["source"] = "model: Eq. (4) with mu = 0 (linear SDOF), exact closed form; synthetic"
    hdr["x0_mm"] = float(x0_mm)
    return make_measurement(hdr, {"t_s": ts, "x": sdof_response(ts, cfg, None, x0_mm)})


def warm_up_model():
    """Compile (or load) the engine's paper loop and its dense output, so that a timed run times no compile."""
    _run_model(validation_config(None), Case(0.0129, 30.0, 1.0, "steel"), 1.0, np.array([0.0, 0.01]), forced=True)
