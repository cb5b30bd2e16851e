"""Glue: figures + tables + benchmarks -> results/report/index.html (self-contained)."""
from impact.pipeline import logged
from impact.report import snakemake_main

with logged(snakemake.log[0]):
    snakemake_main(snakemake)
