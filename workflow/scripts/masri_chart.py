"""Glue: the closed form's existence/stability chart -> dataset."""
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, logged
from impact.outputs.provenance import attributes
from impact.stages.masri.charts import chart_dataset

with logged(snakemake.log[0]):
    p = snakemake.params
    ds = chart_dataset(p.chart, p.structure["beta"], p.structure["force_ratio"])
    ds.attrs.update(title="Masri 2-EIPC stability chart", **attributes())
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
