"""The paper kernel's results do not move: 20 runs frozen before the kernel shared its contact search with
impact.engine (tests/data/frozen_runs.json) are reproduced to 1e-12, as far as the runs themselves allow.

Some of the frozen runs are sensitive: a change of 1e-15 in the forcing phase (one rounding of the kernel's
arithmetic) moves their impact count and amplitude by per cent over 500 periods (long transients of a
CID with e = 0 or 1, runs near a bifurcation).  No reordering of a sum can keep those to 1e-12, so a run is
first measured against itself: run again with the phase moved by a few units of round-off.  A run that
stays within 1e-12 of itself must reproduce its frozen values to 1e-12; a sensitive one must land where
round-off alone already takes it (its frozen values inside the spread of its perturbed runs, widened by
that spread).
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from impact.engine.run import simulate_system as simulate
from impact.model.params import Protocol, System

FROZEN = json.loads((Path(__file__).parent / "data" / "frozen_runs.json").read_text())["cases"]
# phase shifts of a few units of round-off: the ensemble a run's own rounding could have produced
ROUND_OFF = tuple(sign * k * 1e-15 for k in (1, 2, 3, 5, 8, 13) for sign in (1, -1))
TIGHT = 1e-12


def _run(case, shift=0.0):
    system = System(**case["system"])
    return simulate(dataclasses.replace(system, phase=system.phase + shift), case["r"], Protocol(start=case["start"]))


def _quantities(res) -> dict:
    """What a frozen run records: the amplitude, the energy terms and the final state, as arrays."""
    return {"amplitude": np.array([res.amplitude]), "work_input": np.array([res.diagnostics["work_input"]]),
            "impact_losses": np.array([res.diagnostics["impact_losses"]]), "final_state": np.asarray(res.final_state)}


def _ensemble(case):
    """The run and its round-off ensemble: each quantity over the runs (rows), and the impact counts."""
    runs = [_run(case)] + [_run(case, shift) for shift in ROUND_OFF]
    values = {k: np.array([_quantities(r)[k] for r in runs]) for k in _quantities(runs[0])}
    return values, [r.diagnostics["impacts"] for r in runs], runs[0]


def _tight(values) -> bool:
    """Whether a quantity stays within 1e-12 (relative, or absolute for values near 0) over the ensemble."""
    scale = np.maximum(np.abs(values[0]), 1.0)
    return bool(np.all(np.abs(values - values[0]) <= TIGHT * scale))


@pytest.mark.parametrize("case", FROZEN, ids=[f"{c['system']['kind']}-{i}" for i, c in enumerate(FROZEN)])
def test_frozen_run_is_reproduced(case):
    values, counts, res = _ensemble(case)
    if min(counts) == max(counts):
        assert res.diagnostics["impacts"] == case["impacts"]
    else:  # sensitive: the frozen count inside the ensemble's range, widened twice by its width
        width = max(counts) - min(counts)
        assert min(counts) - 2 * width <= case["impacts"] <= max(counts) + 2 * width, (case["impacts"], counts)
    for key, runs in values.items():
        frozen = np.atleast_1d(np.asarray(case[key], dtype=float))
        if _tight(runs):
            np.testing.assert_allclose(runs[0], frozen, rtol=TIGHT, atol=TIGHT, err_msg=key)
        else:
            # one more member of the round-off ensemble: a sample of n = 13 misses the range of the others
            # one time in seven, so the range is widened twice by its width (and never below 1e-12)
            lo, hi = runs.min(axis=0), runs.max(axis=0)
            slack = 2.0 * np.maximum(hi - lo, TIGHT * np.maximum(np.abs(runs[0]), 1.0))
            assert np.all((lo - slack <= frozen) & (frozen <= hi + slack)), (key, frozen, lo, hi)
    assert abs(res.diagnostics["energy_residual"]) < 1e-9


def test_most_frozen_amplitudes_are_held_to_1e_12():
    """The ensemble tolerance is the exception: for most frozen runs the study's measure, the amplitude, and
    the impact count stay within 1e-12 of themselves, and so are held to 1e-12 of the frozen values."""
    tight = []
    for i, case in enumerate(FROZEN):
        values, counts, _ = _ensemble(case)
        if _tight(values["amplitude"]) and min(counts) == max(counts):
            tight.append(i)
    assert len(tight) >= 12, tight
