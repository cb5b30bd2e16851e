"""Glue: one method family on every extreme case -> its rows of the stability table (not yet judged)."""
from impact.outputs.files import write_csv_atomic
from impact.outputs.job_log import logged
from impact.stages.numerics.runs import stability_runs

with logged(snakemake.log[0]) as log:
    runs = stability_runs(snakemake.params.numerics, families=[snakemake.wildcards.family], log=log)
    write_csv_atomic(snakemake.output[0], runs)
