"""Glue: one work-precision case and one method family -> a piece of the dataset."""
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, logged
from impact.stages.numerics.runs import work_precision

with logged(snakemake.log[0]) as log:
    w = snakemake.wildcards
    ds = work_precision(snakemake.params.numerics, cases=[w.case], families=[w.family], log=log)
    ds.attrs.update(title=f"Error against run time: case {w.case}, method family {w.family} (one piece)")
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
