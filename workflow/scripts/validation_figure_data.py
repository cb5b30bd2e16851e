"""Glue: the rig's configuration -> the data of Fig. 3 or Fig. 5 (JSON, tables, records)."""
from impact.outputs.job_log import logged
from impact.stages.validation.steps import adopt_contact_laws, write_fig3_data, write_fig5_data

with logged(snakemake.log[0]):
    adopt_contact_laws(snakemake.input.contact_laws)
    out = snakemake.output
    write = write_fig3_data if snakemake.rule == "validation_fig3_data" else write_fig5_data
    panels = {name: getattr(out, name) for name in out.keys() if name not in ("data", "decay", "sweep")}
    write(snakemake.params.rig, out.data, out.decay, out.sweep, panels)
