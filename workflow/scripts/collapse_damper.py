"""Glue: one damper type on one archetype, every motion traced to collapse -> results/collapse/runs/<building>/<damper>.nc."""
import xarray as xr

from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.collapse.runs import damper_collapse
from impact.stages.ida.runs import design_gap_ratios

with logged(snakemake.log[0]) as log:
    log_versions()
    wc, study = snakemake.wildcards, snakemake.params.study
    gap_ratios = design_gap_ratios(snakemake.input.design)
    ds = damper_collapse(study["collapse"], study["ida"], study["loads"], wc.building, wc.damper,
                         xr.load_dataset(snakemake.input.ida_bare), gap_ratios, xr.load_dataset(snakemake.input.bare))
    log.info("%s %s: gap ratios %s; %d runs, %d at the event cap", wc.building, wc.damper, gap_ratios,
             int(ds["runs"].sum()), int((ds["run_event_cap_reached"] == 1).sum()))
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
