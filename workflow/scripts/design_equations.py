"""Glue: the CID and PID charts -> the design equations' fit and held-out checks, results/design/equations.*"""
from pathlib import Path

import xarray as xr

from impact.outputs.files import write_dataset, write_json_atomic
from impact.outputs.job_log import job_config, log_versions, logged
from impact.stages.design.equations.formulas import checks_dataset, stored, study_kind

with logged(snakemake.log[0]) as log:
    log_versions()
    study, shipped = snakemake.params.study, stored()
    fits, checks = {}, {}
    for path in snakemake.input.charts:
        kind = Path(path).stem.removeprefix("chart_")
        fits[kind], checks[kind] = study_kind(study, kind, xr.load_dataset(path), shipped.get(kind))
        entry = fits[kind]
        log.info("%s: %s on %d chart optima, %s; error over %d held-out points: max %s, p95 %s; published: %s",
                 kind, "fitted" if entry["fitted"] else "not fitted (too few optima): the stored fit checked",
                 len(entry["points"]), entry["coefficients"], entry["checks"], entry["error_max"],
                 entry["error_p95"], entry["published"])
        if entry["fitted"] and shipped.get(kind, {}).get("coefficients") != entry["coefficients"]:
            log.warning("%s: the fit differs from the one the package ships (src/impact/stages/design/equations/fit.json); "
                        "copy results/design/equations.json there to ship it", kind)
    write_json_atomic(snakemake.output.json, fits)
    write_dataset(checks_dataset(fits, checks), snakemake.output.checks, config=job_config(snakemake))
