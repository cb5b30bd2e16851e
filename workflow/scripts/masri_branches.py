"""Glue: closed-form branches along r and runs from rest -> dataset."""
from impact.io import write_dataset
from impact.masri_check import branches_dataset
from impact.params import Protocol
from impact.pipeline import logged
from impact.provenance import attributes

with logged(snakemake.log[0]):
    p = snakemake.params
    protocol = Protocol(periods=p.protocol["periods"], average_from=p.protocol["average_from"])
    ds = branches_dataset(p.branches, p.structure["beta"], p.structure["force_ratio"], protocol, p.starts)
    ds.attrs.update(title="Masri 2-EIPC branches and simulation", **attributes())
    write_dataset(ds, snakemake.output[0])
