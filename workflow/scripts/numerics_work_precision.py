"""Glue: every integrator on the work-precision cases -> dataset and the speed-at-equal-error table."""
from impact.io import write_csv_atomic, write_dataset
from impact.numerics import speed_at_equal_error, work_precision
from impact.pipeline import logged
from impact.provenance import attributes, package_versions

with logged(snakemake.log[0]) as log:
    ds = work_precision(snakemake.params.numerics, log=log)
    ds.attrs.update(title="Error against run time of the exact core and the baseline integrators",
                    Conventions="CF-1.10", packages=str(package_versions()), **attributes())
    write_dataset(ds, snakemake.output.dataset)
    write_csv_atomic(snakemake.output.speed, speed_at_equal_error(ds))
