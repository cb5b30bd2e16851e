"""Glue: every case's JSON -> the grid's tables (per case, per case and r, per amplitude bin)."""
from impact.outputs.job_log import logged
from impact.stages.validation.steps import write_grid_tables

with logged(snakemake.log[0]) as log:
    out = snakemake.output
    write_grid_tables(snakemake.input.cases, out.table, out.curves, out.delta)
    log.info("%d cases", len(snakemake.input.cases))
