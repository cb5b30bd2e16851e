"""Glue: the one case in time -> results/figures/loads_time_history.png/.pdf."""
import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_time_history

with logged(snakemake.log[0]):
    plot_time_history(xr.load_dataset(snakemake.input.dataset), [snakemake.output.png, snakemake.output.pdf])
