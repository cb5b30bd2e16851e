"""The cross-validation stage in one process, outside the workflow: the same steps, the same files."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from impact.outputs.files import write_text_atomic
from impact.rig.config import validation_config
from impact.stages.validation.comparison import _map, _run_case_worker, ablation, run_case
from impact.stages.validation.figures import write_figures
from impact.stages.validation.grid import Case, study_cases
from impact.stages.validation.steps import (
    FIG3_RECORDS,
    FIG5_RECORDS,
    _write_records,
    claims_of,
    grid_tables,
    write_contact_laws,
    write_csv,
    write_drop_tests,
    write_fig3_data,
    write_fig5_data,
)


def run_validation(cfg: dict | None, out_dir, cases=None, *, smoke: bool = False, processes: int | None = None,
                   figures: bool = True, write_all_records: bool = False, ablate: bool = False):
    """The cross-validation stage in one process, into ``out_dir`` (the workflow runs it as rules).

    Runs every case (default: the whole grid; ``smoke=True``: the smoke subset with its shortened
    protocol; or the given ``cases``: Case objects, ids or dicts) in ``processes`` worker processes
    and writes the files the workflow's rules write, under the same names:
    ``validation_table.csv``, ``validation_curves.csv``, ``validation_delta.csv``,
    ``drop_tests.csv`` (records under ``records/drop_tests``), ``claims.json`` and, with
    ``figures``, ``fig3``/``fig5`` (PNG, PDF, data and records) and ``fig4_histories.png``;
    with ``ablate``, ``ablation.csv``; with ``write_all_records``, every record of the grid under
    ``records/grid/`` (about 1 GB for the full grid).  Returns the table (a DataFrame).
    """
    cfg = validation_config(cfg, smoke=smoke)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cases = study_cases(cfg, smoke) if cases is None else [Case.of(c) for c in cases]
    nproc = int(processes if processes is not None else cfg["processes"])
    write_contact_laws(cfg, out / "contact_laws.json")  # solved here once; forked workers inherit it
    results = _map(_run_case_worker, [(cfg, c, None) for c in cases], nproc)
    table, curves, delta = grid_tables(results)
    for frame, name in ((table, "validation_table"), (curves, "validation_curves"), (delta, "validation_delta")):
        write_csv(frame, out / f"{name}.csv")
    write_drop_tests(cfg, out / "drop_tests.csv", out / "records" / "drop_tests")
    f3 = f5 = None
    if figures:
        folders = {name: out / "records" / name for name in FIG3_RECORDS + FIG5_RECORDS}
        f3 = write_fig3_data(cfg, out / "fig3_data.json", out / "fig3a_decay.csv", out / "fig3b_sweep.csv", folders)
        f5 = write_fig5_data(cfg, out / "fig5_data.json", out / "fig5a_decay.csv", out / "fig5b_sweep.csv", folders)
        write_figures(out / "fig3_data.json", out / "fig5_data.json", [out / "fig3.png", out / "fig3.pdf"],
                      [out / "fig5.png", out / "fig5.pdf"], [out / "fig4_histories.png"])
    if write_all_records:
        for c in cases:
            res = run_case(cfg, c, keep_records=True)
            for who in ("model", "rig"):
                _write_records(out / "records" / "grid" / c.id, res.records["sweep"][who])
                _write_records(out / "records" / "grid" / c.id, res.records["decay"][who])
    if ablate:
        write_csv(ablation(cfg, processes=nproc), out / "ablation.csv")
    claims = claims_of(cfg, table, curves, f3, f5, pd.read_csv(out / "drop_tests.csv"), smoke=smoke)
    write_text_atomic(out / "claims.json", json.dumps(claims, indent=2, sort_keys=True) + "\n")
    return table
