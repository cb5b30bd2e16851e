"""Glue: from-rest, continuation and ensemble datasets -> X_m against g."""
import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_coexistence

with logged(snakemake.log[0]):
    rest = xr.load_dataset(snakemake.input.from_rest)
    continuation = {}
    for path in snakemake.input.continuation:
        ds = xr.load_dataset(path)
        continuation[ds.attrs["sweep_mode"]] = ds
    ensemble = xr.load_dataset(snakemake.input.ensemble)
    plot_coexistence(snakemake.params.spec, rest, continuation, ensemble,
                     [snakemake.output.png, snakemake.output.pdf])
