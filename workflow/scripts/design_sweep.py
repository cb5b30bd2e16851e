"""Glue: one chart sweep on the charts' frequency window -> results/design/sweeps/<curve>.nc."""
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.design import chart_config
from impact.stages.sweeps import run_curve

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    log.info("chart curve %s", study["spec"])
    write_dataset(run_curve(chart_config(study), study["spec"]), snakemake.output[0], config=job_config(snakemake))
