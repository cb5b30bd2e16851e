"""Glue: the sweeps' optimum gaps and the TMD optimum -> the robustness stage's design points."""
import json

import xarray as xr

from impact.outputs.files import write_json_atomic
from impact.outputs.job_log import logged
from impact.stages.robustness.designs import designs_from_study, optima_from_sweeps

with logged(snakemake.log[0]) as log:
    optima = optima_from_sweeps(xr.load_dataset(path) for path in snakemake.input.sweeps)
    tmd = json.loads(open(snakemake.input.tmd).read())
    designs = designs_from_study(snakemake.params.study, optima, tmd)
    for name, fields in designs.items():
        log.info("%s: %s", name, fields)
    write_json_atomic(snakemake.output[0], designs)
