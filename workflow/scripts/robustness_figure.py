"""Glue: every design's dataset -> X_m against each variation (results/figures/robustness.png/.pdf)."""
from pathlib import Path

import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_robustness

with logged(snakemake.log[0]):
    designs = {Path(p).stem: xr.load_dataset(p) for p in snakemake.input.designs}
    plot_robustness(designs, [snakemake.output.png, snakemake.output.pdf])
