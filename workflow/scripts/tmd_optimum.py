"""Glue: the optimum TMD -> results/tables/tmd_optimum.json."""
from impact.closed_form.tmd import den_hartog
from impact.closed_form.tmd_minimax import tmd_optimum
from impact.outputs.files import write_json_atomic
from impact.outputs.job_log import logged

with logged(snakemake.log[0]) as log:
    p = snakemake.params
    best = tmd_optimum(p.mu, p.beta, force_ratio=p.force_ratio)
    out = {k: best[k] for k in ("f", "beta_t", "peak_amplitude", "X_m")}
    out.update(mu=p.mu, beta=p.beta, force_ratio=p.force_ratio, den_hartog=den_hartog(p.mu))
    log.info("optimum %s", out)
    write_json_atomic(snakemake.output[0], out)
