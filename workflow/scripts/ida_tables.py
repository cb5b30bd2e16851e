"""Glue: the IDA dataset -> the verdicts per building, damper and record group, and the fragility fits."""
import xarray as xr

from impact.outputs.files import write_csv_atomic
from impact.outputs.job_log import logged
from impact.stages.ida.tables import fragility, verdicts

with logged(snakemake.log[0]) as log:
    study = snakemake.params.study
    ds = xr.load_dataset(snakemake.input.dataset)
    table = verdicts(ds, study, study["design_sa_g"])
    log.info("%s", table.to_string())
    write_csv_atomic(snakemake.output.verdicts, table)
    write_csv_atomic(snakemake.output.fragility, fragility(ds, study["drift_limits"]))
