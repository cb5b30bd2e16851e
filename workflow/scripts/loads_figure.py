"""Glue: the loads datasets -> peak roof ratio against PGA per building and damper."""
from pathlib import Path

import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_loads_reduction

with logged(snakemake.log[0]):
    datasets = {Path(p).stem: xr.load_dataset(p) for p in snakemake.input.datasets}
    plot_loads_reduction(datasets, [snakemake.output.png, snakemake.output.pdf])
