"""Glue: the rig's configuration -> each wall's calibrated contact damping, shared by the stage's jobs."""
from impact.outputs.job_log import logged
from impact.stages.validation.steps import write_contact_laws

with logged(snakemake.log[0]) as log:
    for wall in write_contact_laws(snakemake.params.rig, snakemake.output[0]):
        log.info("%s: e = %.4g, n = %g, chi = %.12g", wall["wall"], wall["e"], wall["n"], wall["chi"])
