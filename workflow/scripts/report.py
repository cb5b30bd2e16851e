"""Glue: figures + tables + benchmarks -> results/report/index.html (self-contained)."""
from impact.outputs.job_log import logged
from impact.outputs.report import snakemake_main

with logged(snakemake.log[0]):
    snakemake_main(snakemake)
