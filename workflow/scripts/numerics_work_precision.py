"""Glue: the pieces (case x method family) -> the work-precision dataset and the speed-at-equal-error table."""
import xarray as xr

from impact.outputs.files import write_csv_atomic, write_dataset
from impact.outputs.job_log import job_config, logged
from impact.outputs.provenance import package_versions
from impact.stages.numerics.tables import combine_work_precision, speed_at_equal_error

with logged(snakemake.log[0]) as log:
    ds = combine_work_precision([xr.load_dataset(p) for p in snakemake.input.pieces], snakemake.params.numerics)
    ds.attrs.update(title="Error against run time of the exact core and the baseline integrators",
                    packages=str(package_versions()))
    write_dataset(ds, snakemake.output.dataset, config=job_config(snakemake))
    write_csv_atomic(snakemake.output.speed, speed_at_equal_error(ds))
    log.info("%d pieces joined", len(snakemake.input.pieces))
