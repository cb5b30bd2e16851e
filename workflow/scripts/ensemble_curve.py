"""Glue: one curve over an ensemble of starting states -> netCDF."""
import json

from impact.model.params import Protocol
from impact.outputs.files import write_dataset
from impact.outputs.job_log import job_config, log_versions, logged
from impact.outputs.provenance import attributes
from impact.stages.coexistence import ensemble_members, run_ensemble

with logged(snakemake.log[0]) as log:
    log_versions()
    study = snakemake.params.study
    ens = snakemake.params.ensemble
    cfg = {key: study[key] for key in ("structure", "protocol", "friction") if key in study}
    members = ensemble_members(int(ens.get("members", 16)), int(ens.get("seed", 20261122)))
    protocol = Protocol(periods=cfg["protocol"]["periods"], average_from=cfg["protocol"]["average_from"])
    ds = run_ensemble(cfg, study["spec"], members, protocol)
    ds.attrs.update(title="Initial-condition ensemble of a CID curve",
                    seed=int(ens.get("seed", 20261122)), parameters=json.dumps(study["spec"]),
                    config=json.dumps(cfg, sort_keys=True), **attributes())
    write_dataset(ds, snakemake.output[0], config=job_config(snakemake))
