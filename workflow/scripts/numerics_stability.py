"""Glue: every family's runs on the extreme cases -> the stability table, judged against the exact core."""
import pandas as pd

from impact.outputs.files import write_csv_atomic
from impact.outputs.job_log import logged
from impact.stages.numerics.tables import stability_table

with logged(snakemake.log[0]):
    # round_trip: every number as the piece wrote it, so the judgement sees the runs' own values
    pieces = [pd.read_csv(p, float_precision="round_trip") for p in snakemake.input.pieces]
    write_csv_atomic(snakemake.output.table, stability_table(pieces, snakemake.params.numerics))
