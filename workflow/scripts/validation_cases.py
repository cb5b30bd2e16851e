"""Glue: every case of one wall material -> model against rig, one JSON file and one log line per case."""
from impact.outputs.job_log import logged
from impact.stages.validation.grid import Case
from impact.stages.validation.steps import with_contact_laws, write_case

with logged(snakemake.log[0]) as log:
    rig = with_contact_laws(snakemake.params.rig, snakemake.input.contact_laws)
    for case, path in zip(snakemake.params.cases, snakemake.output):
        result = write_case(rig, Case.of(case), path)
        log.info("%s: x_max model %.4g mm, rig %.4g mm", result.row["case"], result.row["model_xmax_mm"],
                 result.row["rig_xmax_mm"])
