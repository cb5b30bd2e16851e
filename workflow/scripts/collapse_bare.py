"""Glue: one archetype, bare: its design, pushover and every motion traced to collapse ->
results/collapse/runs/<building>/bare.nc."""
import xarray as xr

from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.collapse.p695 import counted_median
from impact.stages.collapse.runs import bare_collapse

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    ds = bare_collapse(study["collapse"], study["ida"], study["loads"], snakemake.wildcards.building,
                       xr.load_dataset(snakemake.input.ida_bare))
    log.info("%s bare: V_max/W %.3f, mu_T %.2f (%s); %d runs, %d at the event cap; median collapse Sa %.3g g",
             snakemake.wildcards.building, ds.attrs["v_max_over_w"], ds.attrs["mu_T"], ds.attrs["ultimate_by"],
             int(ds["runs"].sum()), int((ds["run_event_cap_reached"] == 1).sum()), counted_median(ds["collapse_sa"].values))
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
