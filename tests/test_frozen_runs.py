"""The paper kernel's results do not move: 20 runs frozen before the kernel shared its contact search with
impact.core (tests/data/frozen_runs.json) are reproduced to 1e-12."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from impact.params import Protocol, System
from impact.simulate import simulate

FROZEN = json.loads((Path(__file__).parent / "data" / "frozen_runs.json").read_text())["cases"]


@pytest.mark.parametrize("case", FROZEN, ids=[f"{c['system']['kind']}-{i}" for i, c in enumerate(FROZEN)])
def test_frozen_run_is_reproduced(case):
    system = System(**case["system"])
    res = simulate(system, case["r"], Protocol(start=case["start"]))
    assert res.diagnostics["impacts"] == case["impacts"]
    assert res.amplitude == pytest.approx(case["amplitude"], rel=1e-12, abs=1e-15)
    for key in ("work_input", "impact_losses"):
        assert res.diagnostics[key] == pytest.approx(case[key], rel=1e-12, abs=1e-15)
    np.testing.assert_allclose(res.final_state, case["final_state"], rtol=1e-12, atol=1e-12)
