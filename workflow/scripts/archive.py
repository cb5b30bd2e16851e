"""Glue: the run's datasets, figures, tables, report, config -> results/archive/impact-study-<commit>.tar.gz."""
from impact.outputs.archive import snakemake_main
from impact.outputs.job_log import logged

with logged(snakemake.log[0]):
    snakemake_main(snakemake)
