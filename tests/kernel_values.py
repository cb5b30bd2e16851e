"""Run as a script by tests/test_kernels.py, once per kernel set: the engine's numbers on the smoke study's loads
scenes, each with the spread a 1e-15 change of the record's scale gives it (its round-off sensitivity).

Prints one JSON object: the kernels this process ran, and per quantity its value and its spread.
"""

from __future__ import annotations

import json

import numpy as np

from impact import kernels
from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.records import load_record
from impact.model.scene import Damper, GroundMotion, Scene

G = 9.80665
#: scale factors a few units of round-off from 1: the ensemble a run's own rounding could have produced
ROUND_OFF = tuple(1.0 + sign * k * 1e-15 for k in (1, 2, 3) for sign in (1, -1))


def scenes():
    """The smoke study's loads building (3 storeys, T1 = 1 s, 2 %) bare and with a CID of 2 % of its mass,
    under El Centro and Northridge at 0.35 g: the values a kernel set moved (issue 47)."""
    building = Building.uniform(3, 1.0, 0.02)
    cid = Damper("cid", 0.02 * building.total_mass, gap=0.05, e=0.5)
    for name in ("elcentro", "northridge"):
        rec = load_record(name)
        for label, dampers in (("bare", ()), ("cid", (cid,))):
            yield f"{name}/{label}", building, dampers, rec.scaled_to_pga_g(0.35) * G, rec.dt


def measures(building, dampers, accel, dt) -> dict:
    res = simulate_scene(Scene(building, dampers, GroundMotion(accel, dt)), record=10_000 if dampers else 0)
    out = {"peak_roof": res.peak_roof_displacement, "rms_roof": res.rms_roof_displacement}
    if dampers:
        out["impulse_mean"] = float(np.mean(np.abs(res.records["impulse"])))
        out["impacts"] = float(res.impacts)
    return out


def main() -> None:
    values = {}
    for name, building, dampers, accel, dt in scenes():
        base = measures(building, dampers, accel, dt)
        ensemble = [measures(building, dampers, accel * s, dt) for s in ROUND_OFF]
        for key, value in base.items():
            runs = [value] + [e[key] for e in ensemble]
            values[f"{name}:{key}"] = {"value": value, "spread": max(runs) - min(runs)}
    print(json.dumps({"kernels": kernels.kernels(), "values": values}))


if __name__ == "__main__":
    main()
