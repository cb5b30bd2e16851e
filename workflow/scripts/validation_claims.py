"""Glue: the grid's tables, the figures' data and the drop tests -> the paper's Sect. 3 claims."""
from impact.outputs.job_log import logged
from impact.stages.validation.steps import write_claims

with logged(snakemake.log[0]):
    i = snakemake.input
    write_claims(snakemake.params.rig, i.table, i.curves, i.fig3, i.fig5, i.drop_tests, snakemake.output[0],
                 smoke=bool(snakemake.params.smoke))
