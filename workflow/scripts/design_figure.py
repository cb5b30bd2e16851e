"""Glue: the charts -> results/figures/design_charts.png/.pdf."""
from pathlib import Path

import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_design_charts

with logged(snakemake.log[0]):
    charts = {Path(p).stem.removeprefix("chart_"): xr.load_dataset(p) for p in snakemake.input.charts}
    plot_design_charts(charts, [snakemake.output.png, snakemake.output.pdf])
