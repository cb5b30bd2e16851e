"""Glue: every design's dataset -> Table 1 of the paper with our numbers beside its words."""
from pathlib import Path

import xarray as xr

from impact.outputs.files import write_csv_atomic
from impact.outputs.job_log import logged
from impact.stages.robustness.table import table1_measured

with logged(snakemake.log[0]) as log:
    designs = {Path(p).stem: xr.load_dataset(p) for p in snakemake.input.designs}
    table = table1_measured(designs)
    log.info("%s", table.to_string())
    write_csv_atomic(snakemake.output[0], table)
