"""Glue: the rig configuration -> model-vs-rig tables, claims and Figs. 3 and 5 (synthetic records)."""
from pathlib import Path

import yaml

from impact.experiment.validation import run_validation
from impact.pipeline import logged

with logged(snakemake.log[0]) as log:
    cfg = yaml.safe_load(Path(snakemake.input.rig_config).read_text())
    table = run_validation(cfg, Path(snakemake.output.table).parent, smoke=bool(snakemake.params.smoke),
                           processes=snakemake.threads)
    log.info("%d cases", len(table))
