"""Glue: one archetype's runs -> its pushover, IDA curves to collapse and collapse fragility curves."""
import xarray as xr

from impact.outputs.collapse_figures import plot_collapse_archetype
from impact.outputs.job_log import logged

with logged(snakemake.log[0]):
    bare = xr.load_dataset(snakemake.input.bare)
    dampers = {ds.attrs["damper"]: ds for ds in map(xr.load_dataset, snakemake.input.dampers)}
    plot_collapse_archetype(bare, dampers, snakemake.wildcards.building, [snakemake.output.png, snakemake.output.pdf])
