"""Glue: every archetype's runs -> the collapse margins, each damper's verdict, and the best damper per group."""
import pandas as pd
import xarray as xr

from impact.outputs.files import write_csv_atomic, write_text_atomic
from impact.outputs.job_log import logged
from impact.stages.collapse.tables import best, margins, performance_groups, summary, verdicts

with logged(snakemake.log[0]) as log:
    study = snakemake.params.study
    dampers = {}
    for path in snakemake.input.dampers:
        ds = xr.load_dataset(path)
        dampers.setdefault(ds.attrs["building"], {})[ds.attrs["damper"]] = ds
    tables, judged = [], []
    for path in snakemake.input.bare:
        bare = xr.load_dataset(path)
        mine = dampers.get(bare.attrs["building"], {})
        tables.append(margins(bare, mine, study))
        judged.append(verdicts(tables[-1], bare, mine, study))
    table, verdict = pd.concat(tables, ignore_index=True), pd.concat(judged, ignore_index=True)
    log.info("%s", table.to_string())
    write_csv_atomic(snakemake.output.margins, table)
    write_csv_atomic(snakemake.output.verdicts, verdict)
    top, groups = best(verdict, study["resolution"]), performance_groups(table, study["resolution"])
    write_csv_atomic(snakemake.output.best, top)
    write_csv_atomic(snakemake.output.groups, groups)
    write_text_atomic(snakemake.output.summary, summary(table, verdict, top, groups))
