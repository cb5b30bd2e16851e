"""Glue: one curve's sweeps -> results/sweeps/<curve>.nc."""
from impact.io import write_dataset
from impact.pipeline import log_versions, logged
from impact.study import run_curve

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    cfg = {key: study[key] for key in ("structure", "protocol", "friction") if key in study}
    log.info("curve %s", study["spec"])
    write_dataset(run_curve(cfg, study["spec"]), snakemake.output[0])
