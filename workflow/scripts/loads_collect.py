"""Glue: every building's runs -> results/loads/<family>.nc (dims building, damper, ...)."""
from pathlib import Path

import xarray as xr

from impact.outputs.files import write_dataset
from impact.outputs.job_log import logged
from impact.stages.loads.tables import collect

with logged(snakemake.log[0]):
    bare = {Path(p).parent.name: xr.load_dataset(p) for p in snakemake.input.bare}
    dampers = {(Path(p).parent.name, Path(p).stem): xr.load_dataset(p) for p in snakemake.input.dampers}
    datasets = collect(bare, dampers)
    for path in snakemake.output:
        write_dataset(datasets[Path(path).stem], path)
