"""Glue: closed-form branches along r and runs from rest -> dataset."""
from impact.model.params import Protocol
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, logged
from impact.outputs.provenance import attributes
from impact.stages.masri.check import branches_dataset

with logged(snakemake.log[0]):
    p = snakemake.params
    protocol = Protocol(periods=p.protocol["periods"], average_from=p.protocol["average_from"])
    ds = branches_dataset(p.branches, p.structure["beta"], p.structure["force_ratio"], protocol, p.starts)
    ds.attrs.update(title="Masri 2-EIPC branches and simulation", **attributes())
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
