"""Glue: coexistence datasets -> per-curve table and the e-trend statement."""
import json

import xarray as xr

from impact.model.params import curve_id
from impact.outputs.files import write_csv_atomic, write_json_atomic
from impact.outputs.job_log import logged
from impact.stages.tables import X_M_AT_OPTIMUM, closed_form_statement, coexistence_table, e_trend_statement

with logged(snakemake.log[0]) as log:
    paper = {curve_id(spec): value for _, _, spec, value in X_M_AT_OPTIMUM}
    rest, e_of = {}, {}
    for path in snakemake.input.from_rest:
        ds = xr.load_dataset(path)
        spec = json.loads(ds.attrs["curve"])
        rest[spec["id"]] = ds
        e_of[spec["id"]] = spec["e"]
    continuation = {}
    for path in snakemake.input.continuation:
        ds = xr.load_dataset(path)
        continuation[(json.loads(ds.attrs["curve"])["id"], ds.attrs["sweep_mode"])] = ds
    ensembles = {}
    for path in snakemake.input.ensemble:
        ds = xr.load_dataset(path)
        ensembles[ds.attrs["curve"]] = ds
    table = coexistence_table(paper, rest, continuation, ensembles)
    statement = {"e_trend": e_trend_statement(table, e_of), "closed_form_reading": closed_form_statement(table, e_of)}
    log.info("%s\n%s", table.T.to_string(), statement)
    write_csv_atomic(snakemake.output.table, table)
    write_json_atomic(snakemake.output.statement, statement)
