"""Glue: the rig's configuration -> synthetic drop tests and e recovered by Eq. (3b)."""
from impact.outputs.job_log import logged
from impact.stages.validation.steps import with_contact_laws, write_drop_tests

with logged(snakemake.log[0]):
    rig = with_contact_laws(snakemake.params.rig, snakemake.input.contact_laws)
    write_drop_tests(rig, snakemake.output.table, snakemake.output.records)
