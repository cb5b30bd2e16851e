"""Glue: the loads datasets -> the best damper per building and intensity, and each damper's verdicts."""
from pathlib import Path

import xarray as xr

from impact.outputs.files import write_csv_atomic
from impact.outputs.job_log import logged
from impact.stages.loads.tables import best_damper_table, verdict_table

with logged(snakemake.log[0]) as log:
    datasets = {Path(p).stem: xr.load_dataset(p) for p in snakemake.input.datasets}
    best, verdicts = best_damper_table(datasets), verdict_table(datasets)
    log.info("%s", verdicts.to_string())
    write_csv_atomic(snakemake.output.best, best)
    write_csv_atomic(snakemake.output.verdicts, verdicts)
