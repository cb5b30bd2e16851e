"""Glue: one damper's chart sweeps (or the TMD's closed form) -> results/design/chart_<damper>.nc."""
import xarray as xr

from impact.model.kinds import KINDS
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, logged
from impact.stages.design import chart_config, impact_chart, tmd_chart, tmd_mu_grid
from impact.stages.sweeps import freq_grid

with logged(snakemake.log[0]) as log:
    study, kind = snakemake.params.study, snakemake.wildcards.kind
    if not KINDS[kind].walls:  # the TMD's chart is its closed form
        structure = study["structure"]
        chart = tmd_chart(tmd_mu_grid(study["design"]), structure["beta"], structure["force_ratio"],
                          study["protocol"], freq_grid(chart_config(study)))
    else:
        chart = impact_chart(kind, [xr.load_dataset(p) for p in snakemake.input.sweeps])
    log.info("%s chart: X_m %.4f to %.4f", kind, float(chart["X_m"].min()), float(chart["X_m"].max()))
    write_dataset(chart, snakemake.output[0], config=job_config(snakemake))
