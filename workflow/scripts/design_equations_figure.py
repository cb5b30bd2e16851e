"""Glue: the design equations' held-out checks -> results/figures/design_equations.png/.pdf."""
import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_design_equations

with logged(snakemake.log[0]):
    plot_design_equations(xr.load_dataset(snakemake.input.checks), [snakemake.output.png, snakemake.output.pdf])
