"""Glue: every building's runs -> results/ida/ida.nc (dims building, damper, mass_ratio, motion, level)."""
from pathlib import Path

import xarray as xr

from impact.outputs.files import write_dataset
from impact.outputs.job_log import logged
from impact.stages.ida.tables import collect

with logged(snakemake.log[0]):
    bare = {Path(p).parent.name: xr.load_dataset(p) for p in snakemake.input.bare}
    dampers = {(Path(p).parent.name, Path(p).stem): xr.load_dataset(p) for p in snakemake.input.dampers}
    write_dataset(collect(bare, dampers), snakemake.output[0])
