"""Glue: one work-precision case and one method family -> a piece of the dataset."""
from impact.io import write_dataset
from impact.numerics import work_precision
from impact.pipeline import logged

with logged(snakemake.log[0]) as log:
    w = snakemake.wildcards
    ds = work_precision(snakemake.params.numerics, cases=[w.case], families=[w.family], log=log)
    ds.attrs.update(title=f"Error against run time: case {w.case}, method family {w.family} (one piece)")
    write_dataset(ds, snakemake.output[0])
