"""Glue: continuation datasets (+ closed form at that gap) -> frequency response with hysteresis."""
import numpy as np
import xarray as xr

from impact.model.params import a_max
from impact.outputs.job_log import logged
from impact.outputs.plotting import plot_hysteresis
from impact.stages.masri.charts import branches

with logged(snakemake.log[0]):
    p = snakemake.params
    rest = xr.load_dataset(snakemake.input.from_rest)
    continuation = {}
    for path in snakemake.input.continuation:
        ds = xr.load_dataset(path)
        continuation[ds.attrs["sweep_mode"]] = ds
    g = float(rest["gap_ratio"].sel(gap_ratio=p.gap_ratio, method="nearest"))
    beta, xst = p.structure["beta"], p.structure["force_ratio"]
    r = rest["freq_ratio"].values
    fine = np.linspace(r.min(), r.max(), 8 * len(r) - 7)
    closed = branches(p.spec["mu"], p.spec["e"], beta, xst, g, fine) if p.spec["e"] > 0 else None
    plot_hysteresis(p.spec, continuation, rest, closed, g, xst / a_max(beta, xst),
                    [snakemake.output.png, snakemake.output.pdf])
