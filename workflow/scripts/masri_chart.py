"""Glue: the closed form's existence/stability chart -> dataset."""
from impact.io import write_dataset
from impact.masri_check import chart_dataset
from impact.pipeline import logged
from impact.provenance import attributes

with logged(snakemake.log[0]):
    p = snakemake.params
    ds = chart_dataset(p.chart, p.structure["beta"], p.structure["force_ratio"])
    ds.attrs.update(title="Masri 2-EIPC stability chart", **attributes())
    write_dataset(ds, snakemake.output[0])
