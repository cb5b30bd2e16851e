"""Glue: one chart sweep on the charts' frequency window -> results/design/sweeps/<curve>.nc."""
from impact.design import chart_config
from impact.io import write_dataset
from impact.pipeline import log_versions, logged
from impact.study import run_curve

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    log.info("chart curve %s", study["spec"])
    write_dataset(run_curve(chart_config(study), study["spec"]), snakemake.output[0])
