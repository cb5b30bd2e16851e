"""Glue: closed-form check datasets -> stability chart and branch figures."""
import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_branches, plot_stability_chart

with logged(snakemake.log[0]):
    with xr.open_dataset(snakemake.input.chart) as chart:
        plot_stability_chart(chart.load(), [snakemake.output.chart_png, snakemake.output.chart_pdf])
    with xr.open_dataset(snakemake.input.branches) as branches:
        plot_branches(branches.load(), [snakemake.output.branches_png, snakemake.output.branches_pdf])
