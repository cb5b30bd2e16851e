"""Glue: one damper type on one building over the ladder -> results/ida/runs/<building>/<damper>.nc."""
import xarray as xr

from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.ida.runs import damper_runs, design_gap_ratios

with logged(snakemake.log[0]) as log:
    log_versions()
    wc, study = snakemake.wildcards, snakemake.params.study
    gap_ratios = design_gap_ratios(snakemake.input.design)
    ds = damper_runs(study["ida"], study["loads"], wc.building, wc.damper, xr.load_dataset(snakemake.input.bare),
                     gap_ratios)
    log.info("%s %s: gap ratios %s; %d runs stopped at the event cap", wc.building, wc.damper, gap_ratios,
             int(ds["event_cap_reached"].sum()))
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
