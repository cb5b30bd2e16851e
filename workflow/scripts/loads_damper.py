"""Glue: one damper type on one building -> results/loads/runs/<building>/<damper>.nc."""
import xarray as xr

from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.loads.runs import damper_runs

with logged(snakemake.log[0]) as log:
    log_versions()
    wc = snakemake.wildcards
    ds = damper_runs(snakemake.params.study, wc.building, wc.damper, xr.load_dataset(snakemake.input.bare))
    log.info("%s %s: mean peak roof ratio under the records %.3f", wc.building, wc.damper,
             float(ds["records_peak_roof_ratio"].mean()))
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
