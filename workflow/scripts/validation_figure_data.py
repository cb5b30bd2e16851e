"""Glue: the rig's configuration -> the data of Fig. 3 or Fig. 5 (JSON, tables, records)."""
from impact.outputs.job_log import logged
from impact.stages.validation.steps import with_contact_laws, write_fig3_data, write_fig5_data

with logged(snakemake.log[0]):
    rig = with_contact_laws(snakemake.params.rig, snakemake.input.contact_laws)
    out = snakemake.output
    write = write_fig3_data if snakemake.rule == "validation_fig3_data" else write_fig5_data
    panels = {name: getattr(out, name) for name in out.keys() if name not in ("data", "decay", "sweep")}
    write(rig, out.data, out.decay, out.sweep, panels)
