"""Glue: one case in time (the configured building, record and damper at its best gap)."""
import xarray as xr

from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.loads.runs import time_history

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    case = study["time_history"]
    design = xr.load_dataset(snakemake.input.damper[0])
    gap_ratio = float(design["records_design_gap_ratio"].sel(mass_ratio=case["mass_ratio"]))
    ds = time_history(study, case["building"], case["record"], case["damper"], case["mass_ratio"], gap_ratio,
                      xr.load_dataset(snakemake.input.bare[0]))
    log.info("%d impacts", ds.sizes["impact"])
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
