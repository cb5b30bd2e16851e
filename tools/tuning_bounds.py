"""How a damper's tuning moves the energy balance's round-off: the measurement behind MIN_TUNING and MAX_TUNING.

The probe's first 40 scenes (seed 424242) that have a PID or TMD are run with every such damper set to one tuning,
below the model's range, inside it and above it: the soft side keeps the scenes as drawn (impacts included), the
stiff side makes the springs TMDs (no impacts, so the modal tables' round-off alone shows).  Prints, per tuning,
the largest |energy residual| over the scenes and how many pass the 1e-9 every run balances to.  The model's bounds
are widened for the run, to measure beyond them.  docs/model.md and impact.model.params quote its output.

    python -m impact.kernels tools/tuning_bounds.py    (a few minutes)
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path
from unittest import mock

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from probe import scene_of  # noqa: E402

from impact.engine.run import simulate  # noqa: E402
from impact.model.kinds import KINDS  # noqa: E402
from impact.model.params import ParameterError  # noqa: E402
from impact.model.scene import Damper  # noqa: E402

SEED, SCENES = 424242, 40
SOFT = (0.01, 0.03, 0.1, 0.3)
STIFF = (10.0, 30.0, 100.0, 300.0, 1000.0)


def tuned(damper) -> bool:
    """Whether the damper hangs on a spring tuned to the building (the registry's word, kinds.DamperKind.spring)."""
    return KINDS[damper.kind].spring


def tuned_scenes():
    found, i = [], 0
    while len(found) < SCENES:
        i += 1
        try:
            scene, _ = scene_of(SEED, i - 1)
        except ParameterError:
            continue
        if any(map(tuned, scene.dampers)):
            found.append(scene)
    return found


def soft(scene, t):
    return replace(scene, dampers=tuple(replace(d, tuning=t) if tuned(d) else d for d in scene.dampers))


def stiff(scene, t):
    return replace(scene, dampers=tuple(Damper("tmd", mass=d.mass, tuning=t, damping=d.damping, floor=d.floor,
                                               units=d.units) for d in scene.dampers if tuned(d)))


def main() -> None:
    with mock.patch("impact.model.scene.MIN_TUNING", 1e-3), mock.patch("impact.model.scene.MAX_TUNING", 1e4):
        scenes = tuned_scenes()
        for side, tunings, variant in (("soft, as drawn", SOFT, soft), ("stiff, springs as TMDs", STIFF, stiff)):
            for t in tunings:
                res = np.array([abs(simulate(variant(s, t), measures=("peaks",)).diagnostics["energy_residual"])
                                for s in scenes])
                print(f"{side:24s} tuning {t:7g}: largest |residual| {res.max():.1e}, {np.sum(res > 1e-9)} of "
                      f"{len(res)} beyond 1e-9, median {np.median(res):.1e}", flush=True)


if __name__ == "__main__":
    main()
