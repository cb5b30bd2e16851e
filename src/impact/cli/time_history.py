"""What a command that draws its run asks of the engine, and the drawing: the roof, the first damper unit's stroke
between its walls and its impacts (impact run --plot, impact quake --plot and --series)."""

from __future__ import annotations

import numpy as np

from impact.outputs.datasets import time_history_dataset
from impact.outputs.plotting import plot_time_history

#: impacts kept for a drawn run (more are counted, not drawn); the samples of its time history
PLOT_IMPACTS = 50_000
PLOT_SAMPLES = 20_000


def asked(scene, measures: tuple, step: float | None = None) -> dict:
    """simulate()'s keywords: the measures a command reports and, given a `step`, what --plot draws too: samples
    every `step` (at most PLOT_SAMPLES) and the impact records.  The plotted run is the run reported: it then runs
    on the scene loop."""
    if step is None:
        return {"measures": measures}
    times = np.linspace(0.0, scene.t_end, min(PLOT_SAMPLES, int(scene.t_end / step) + 1))
    return {"measures": (*measures, "samples", "records"), "record": PLOT_IMPACTS, "times": times}


def plot(path: str, scene, res, title: str, length_unit: str, impulse_unit: str, roof_bare=None) -> None:
    """Draw a run's time history (the roof, the first damper unit's stroke between its walls, its impacts)."""
    damper = scene.dampers[0]
    floor = (damper.floor or scene.building.storeys) - 1
    q = res.samples["q"]
    stroke = q[:, scene.building.storeys] - q[:, floor]
    plot_time_history(time_history_dataset(res.samples["t"], q[:, scene.building.storeys - 1], stroke,
                                           0.5 * damper.clearance if damper.has_walls else float("nan"),
                                           res.records["t"], res.records["impulse"], length_unit=length_unit,
                                           impulse_unit=impulse_unit, title=title, kind=damper.kind,
                                           roof_bare=roof_bare), [path])
