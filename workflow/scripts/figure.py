"""Glue: datasets (+ optimum TMD) -> results/figures/<fig>.{png,pdf}."""
import json

import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_figure

with logged(snakemake.log[0]):
    datasets = {}
    for path in snakemake.input.curves:
        with xr.open_dataset(path) as ds:
            datasets[json.loads(ds.attrs["curve"])["id"]] = ds.load()
    tmd = None
    if snakemake.input.tmd:
        with open(snakemake.input.tmd[0]) as fh:
            tmd = json.load(fh)
    plot_figure(snakemake.params.figure, datasets, tmd, [snakemake.output.png, snakemake.output.pdf])
