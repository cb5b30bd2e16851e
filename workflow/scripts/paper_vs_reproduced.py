"""Glue: datasets + optimum TMD -> results/tables/paper_vs_reproduced.csv."""
import json

import xarray as xr

from impact.outputs.files import write_csv_atomic
from impact.outputs.job_log import logged
from impact.stages.tables import paper_vs_reproduced

with logged(snakemake.log[0]) as log:
    datasets = {}
    for path in snakemake.input.curves:
        with xr.open_dataset(path) as ds:
            datasets[json.loads(ds.attrs["curve"])["id"]] = ds.load()
    with open(snakemake.input.tmd) as fh:
        tmd = json.load(fh)
    table = paper_vs_reproduced(datasets, tmd)
    log.info("\n%s", table.to_string())
    write_csv_atomic(snakemake.output[0], table)
