"""Glue: one building, bare, under every ground motion over the ladder -> results/ida/runs/<building>/bare.nc."""
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.ida.runs import bare_runs

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    ds = bare_runs(study["ida"], study["loads"], snakemake.wildcards.building)
    log.info("%s bare: %d ground motions, Sa(T1) as recorded %.3g-%.3g g", snakemake.wildcards.building,
             ds.sizes["motion"], float(ds["sa_record"].min()), float(ds["sa_record"].max()))
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
