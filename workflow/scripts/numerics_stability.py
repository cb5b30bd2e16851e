"""Glue: every integrator on the extreme cases -> the stability table."""
from impact.io import write_csv_atomic
from impact.numerics import stability
from impact.pipeline import logged

with logged(snakemake.log[0]) as log:
    write_csv_atomic(snakemake.output.table, stability(snakemake.params.numerics, log=log))
