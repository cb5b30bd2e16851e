"""The cross-validation stage's files: one function per step, each reading and writing files only.

The workflow runs each step as its own rule (``workflow/rules/validation.smk``): one job per wall
material, writing each case of the grid on it (:func:`write_case`), then the grid's tables (:func:`write_grid_tables`), the drop
tests, the data of Figs. 3 and 5 and the claims; the figures are drawn by :mod:`.figures`, and
:mod:`.standalone` runs every step in one process, for a quick look outside the workflow.  Every file is written
atomically, and every file the workflow keeps is one its rules declare.

Nothing here is the paper's data: every record says ``synthetic: true``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Iterable

import numpy as np
import pandas as pd

from impact.outputs.files import write_text_atomic
from impact.outputs.measurements import Measurement, write_measurement
from impact.rig.simulator import contact_calibrations, with_calibrations
from impact.stages.validation.claims import evaluate_claims, jsonable
from impact.stages.validation.comparison import (
    CaseResult,
    drop_tests,
    fig3_data,
    fig5_data,
    run_case,
)
from impact.stages.validation.grid import Case

# where each figure's records go, under the stage's records folder (one folder per panel)
FIG3_RECORDS = ("fig3a", "fig3b_paper_grid", "fig3b_fine_grid")
FIG5_RECORDS = ("fig5a_pid", "fig5a_bare", "fig5b")


def write_csv(df, path) -> Path:
    """Write a DataFrame as CSV atomically."""
    path = Path(path)
    write_text_atomic(path, df.to_csv(index=False))
    return path


def _write_json(path, obj) -> None:
    # NaN stays NaN (Python's JSON reads it back): a missing number is not a null
    write_text_atomic(Path(path), json.dumps(obj, indent=1, sort_keys=True, allow_nan=True) + "\n")


def _plain(obj):
    """Numbers and arrays as JSON values, NaN kept."""
    return jsonable(obj, keep_nan=True)


def _write_records(folder: Path, recs: Iterable[Measurement]) -> None:
    for rec in recs:
        h = rec.header
        tag = f"r{h['r']:.4f}" if "r" in h else (f"x0_{h['x0_mm']:g}mm" if "x0_mm" in h else "drops")
        src = "rig" if h.get("source", "").startswith("virtual rig") else "model"
        write_measurement(Path(folder) / f"{src}_{h['kind']}_{tag}.csv", rec)


# ----------------------------------------------------------------------------
# the walls' contact laws, calibrated once for every job of the stage
# ----------------------------------------------------------------------------


def write_contact_laws(cfg: dict, path) -> list[dict]:
    """Each wall's calibrated Hunt--Crossley damping chi (:func:`.rig.contact_calibrations`), as JSON."""
    walls = contact_calibrations(cfg)
    _write_json(path, {"walls": walls})
    return walls


def with_contact_laws(cfg: dict, path) -> dict:
    """The rig's configuration with each wall's chi from :func:`write_contact_laws`' file, which the rig then
    uses rather than solving for it again."""
    return with_calibrations(cfg, json.loads(Path(path).read_text())["walls"])


# ----------------------------------------------------------------------------
# one case, and the grid's tables
# ----------------------------------------------------------------------------


def write_case(cfg: dict, case: Case, path) -> CaseResult:
    """Model against rig for one case (:func:`.comparison.run_case`), as one JSON file."""
    res = run_case(cfg, case)
    _write_json(path, _plain({"row": res.row, "curve": res.curve, "delta": res.delta}))
    return res


def read_case(path) -> CaseResult:
    data = json.loads(Path(path).read_text())
    return CaseResult(data["row"], data["curve"], data["delta"])


def grid_tables(results: Iterable[CaseResult]):
    """The grid's three tables: one row per case, per case and r, per case and amplitude bin."""

    results = list(results)
    return (pd.DataFrame([r.row for r in results]), pd.DataFrame([row for r in results for row in r.curve]),
            pd.DataFrame([row for r in results for row in r.delta]))


def write_grid_tables(case_files, table, curves, delta) -> None:
    for frame, path in zip(grid_tables(read_case(f) for f in case_files), (table, curves, delta)):
        write_csv(frame, path)


# ----------------------------------------------------------------------------
# drop tests, and the data of Figs. 3 and 5
# ----------------------------------------------------------------------------


def write_drop_tests(cfg: dict, table, records) -> None:
    recs, frame = drop_tests(cfg)
    write_csv(frame, table)
    for rec in recs:
        write_measurement(Path(records) / f"rig_drop_{rec.header['wall']}_D{rec.header['ball_diameter_mm']:g}mm.csv", rec)


def write_fig3_data(cfg: dict, data, decay, sweep, records: dict) -> dict:
    """Fig. 3's data (JSON, for the plot and the claims), its two tables and its records.

    records: a folder for each of FIG3_RECORDS.
    """

    f3 = fig3_data(cfg, keep_records=True)
    write_csv(f3["decay"], decay)
    rows = [{"grid": g, "r": r, "model_amp_mm": am, "rig_amp_mm": ar}
            for g, sw in f3["sweeps"].items() for r, am, ar in zip(sw["r"], sw["model_amp_mm"], sw["rig_amp_mm"])]
    write_csv(pd.DataFrame(rows), sweep)
    for who in ("model", "rig"):
        _write_records(records["fig3a"], f3["records"]["decay"][who])
        for g in ("paper_grid", "fine_grid"):
            _write_records(records[f"fig3b_{g}"], f3["records"]["sweep"][g][who])
    saved = {k: v for k, v in f3.items() if k != "records"}
    _write_json(data, _plain({**saved, "decay": saved["decay"].to_dict(orient="list")}))
    return f3


def read_fig3_data(path) -> dict:

    data = json.loads(Path(path).read_text())
    return {**data, "decay": pd.DataFrame(data["decay"])}


def write_fig5_data(cfg: dict, data, decay, sweep, records: dict) -> dict:
    """Fig. 5's data (JSON, for the plots and the claims), its two tables and its records.

    records: a folder for each of FIG5_RECORDS.
    """
    f5 = fig5_data(cfg, keep_records=True)
    write_csv(f5["a"]["data"], decay)
    write_csv(f5["b"]["data"], sweep)
    for who in ("model", "rig"):
        for name in FIG5_RECORDS:
            _write_records(records[name], f5["records"][name][who])
    saved = {"a": {**f5["a"], "data": f5["a"]["data"].to_dict(orient="list")},
             "b": {**f5["b"], "data": f5["b"]["data"].to_dict(orient="list")}}
    _write_json(data, _plain(saved))
    return f5


def read_fig5_data(path) -> dict:

    data = json.loads(Path(path).read_text())
    b = data["b"]
    return {"a": {**data["a"], "data": pd.DataFrame(data["a"]["data"])},
            "b": {**b, "data": pd.DataFrame(b["data"]),
                  "histories": {float(r): h for r, h in b["histories"].items()}}}


# ----------------------------------------------------------------------------
# claims and figures
# ----------------------------------------------------------------------------


def claims_of(cfg: dict, table, curves, fig3: dict | None, fig5: dict | None, drops, *, smoke: bool) -> dict:
    """The claims (:func:`.claims.evaluate_claims`), the drop tests' check and what the run covered."""
    claims = evaluate_claims(cfg, table, curves, fig3, fig5)
    claims["drop_tests"] = {"max_abs_error_e": float(np.max(np.abs(drops.e_recovered - drops.e_calibrated))),
                            "note": "Eq. (3b) with the header's mu on synthetic drops"}
    seconds = float(table["time_case_s"].sum()) if len(table) else math.nan
    claims["run"] = {"cases": int(len(table)), "case_seconds": seconds, "smoke": smoke, "synthetic": True,
                     "source": "virtual rig vs Eq. (4) model; not the paper's data"}
    return jsonable(claims)


def write_claims(cfg: dict, table, curves, fig3, fig5, drops, out, *, smoke: bool) -> dict:

    def read(path):
        return pd.read_csv(path, float_precision="round_trip")  # every number as it was written

    claims = claims_of(cfg, read(table), read(curves), read_fig3_data(fig3), read_fig5_data(fig5), read(drops),
                       smoke=smoke)
    write_text_atomic(Path(out), json.dumps(claims, indent=2, sort_keys=True) + "\n")
    return claims
