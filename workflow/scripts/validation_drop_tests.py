"""Glue: the rig's configuration -> synthetic drop tests and e recovered by Eq. (3b)."""
from impact.outputs.job_log import logged
from impact.stages.validation.steps import adopt_contact_laws, write_drop_tests

with logged(snakemake.log[0]):
    adopt_contact_laws(snakemake.input.contact_laws)
    write_drop_tests(snakemake.params.rig, snakemake.output.table, snakemake.output.records)
