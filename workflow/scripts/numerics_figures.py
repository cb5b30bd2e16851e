"""Glue: numerics results -> error-against-run-time figure and the stability heat map."""
import platform

import pandas as pd
import xarray as xr

from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_stability_map, plot_work_precision
from impact.outputs.provenance import package_versions

with logged(snakemake.log[0]):
    versions = ", ".join(f"{k} {v}" for k, v in package_versions().items())
    footer = f"{platform.machine()} {platform.processor() or ''} | {platform.system()} | {versions}"
    plot_work_precision(xr.load_dataset(snakemake.input.dataset), footer,
                        [snakemake.output.work_png, snakemake.output.work_pdf])
    plot_stability_map(pd.read_csv(snakemake.input.stability), [snakemake.output.map_png, snakemake.output.map_pdf])
