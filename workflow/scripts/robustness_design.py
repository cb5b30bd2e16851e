"""Glue: one design point -> its X_m along every variation that applies (results/robustness/<design>.nc)."""
import json

from impact.model.kinds import KINDS, TMD
from impact.model.params import Protocol
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.robustness.designs import Design, grids, stroke_cap
from impact.stages.robustness.runs import design_dataset
from impact.stages.sweeps import freq_grid

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    designs = json.loads(open(snakemake.input.designs).read())
    design = Design(**designs[snakemake.wildcards.design])
    protocol = Protocol(periods=study["protocol"]["periods"], average_from=study["protocol"]["average_from"])
    cap = None if KINDS[design.kind].walls else stroke_cap(designs)
    ds = design_dataset(design, grids(study, designs[TMD]["damping"]), freq_grid(study), protocol, stroke_cap=cap)
    log.info("%s: X_m %.4f at the design point", snakemake.wildcards.design, float(ds["X_m_design"]))
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
