"""Glue: the IDA dataset and fits -> one building's IDA curves, drift ratios over the bare building, fragility."""
import pandas as pd
import xarray as xr

from impact.outputs.ida_figures import plot_ida_building
from impact.outputs.job_log import logged

with logged(snakemake.log[0]):
    ds = xr.load_dataset(snakemake.input.dataset)
    fits = pd.read_csv(snakemake.input.fragility)
    plot_ida_building(ds, fits, snakemake.wildcards.building, snakemake.params.study,
                      [snakemake.output.png, snakemake.output.pdf])
