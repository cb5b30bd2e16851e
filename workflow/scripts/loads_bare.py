"""Glue: one building, bare, under every load of the stage -> results/loads/runs/<building>/bare.nc."""
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.loads.runs import bare_runs

with logged(snakemake.log[0]) as log:
    log_versions()
    ds = bare_runs(snakemake.params.study, snakemake.wildcards.building)
    log.info("%s bare: peak roof %.4g m under records (largest)", snakemake.wildcards.building,
             float(ds["records_peak_roof"].max()))
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
