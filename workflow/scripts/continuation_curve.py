"""Glue: one curve's continuation sweeps (one direction) -> netCDF."""
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.sweeps import run_curve

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    cfg = {key: study[key] for key in ("structure", "protocol", "friction") if key in study}
    log.info("curve %s, %s", study["spec"], snakemake.wildcards.mode)
    write_dataset(run_curve(cfg, study["spec"], mode=snakemake.wildcards.mode), snakemake.output[0], config=job_config(snakemake))
