"""How storeys softened by P-delta move a yielding building's energy balance and peaks: the measurement behind
reading the state off the rows while every storey is elastic (docs/model.md, "Near zero the flow loses digits").

The probe's yielding scenes (tests/probe.draw_yielding_scene, one seed) that have P-delta and a damper are run with
their softest storey's height changed so that its stability coefficient theta = P / (k h) is each of THETAS (a
scene whose post-yield stiffness the model then refuses is left out at that theta).  Prints one JSON line per
scene and theta: the energy residual, whether the run stopped at its event cap, and the peak drifts.  Run it under
two versions of the engine, or two OpenBLAS kernel sets (IMPACT_OPENBLAS_CORETYPE), and compare the lines.

    python -m impact.kernels tools/soft_storeys.py [--seed 4242] [--scenes 60] [--only 27,60]    (a few minutes)
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from probe import draw_yielding_scene  # noqa: E402

from impact.engine.run import simulate  # noqa: E402
from impact.model.params import ParameterError  # noqa: E402

THETAS = (0.3, 0.5, 0.7, 0.9, 0.95)


def soft_scenes(seed: int, count: int):
    """The first `count` drawn yielding scenes with P-delta and a damper, numbered from 1 (draws the model refuses
    are skipped, as the probe skips them)."""
    rng = np.random.default_rng(seed)
    found = 0
    while found < count:
        try:
            scene, _ = draw_yielding_scene(rng)
        except ParameterError:
            continue
        if scene.building.p_delta and scene.dampers:
            found += 1
            yield found, scene


def softened(scene, theta: float):
    """The scene with its softest storey made taller, or shorter, so that its stability coefficient is theta."""
    thetas = scene.stability_coefficients()
    i = int(np.argmax(thetas))
    heights = scene.building.storey_height.copy()
    heights[i] *= thetas[i] / theta
    return replace(scene, building=replace(scene.building, storey_height=heights))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=4242)
    ap.add_argument("--scenes", type=int, default=60)
    ap.add_argument("--only", default="", help="comma-separated scene numbers to run (default: every one)")
    args = ap.parse_args(argv)
    only = {int(i) for i in args.only.split(",") if i}
    for number, scene in soft_scenes(args.seed, args.scenes):
        if only and number not in only:
            continue
        for theta in THETAS:
            try:
                result = simulate(softened(scene, theta), measures=("peaks",))
            except ParameterError:
                continue
            diag = result.diagnostics
            print(json.dumps({"scene": number, "theta": theta, "energy_residual": diag["energy_residual"],
                              "event_cap_reached": diag["event_cap_reached"],
                              "peak_drifts": [float(x) for x in result.peak_drifts]}), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
