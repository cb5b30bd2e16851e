# Stage 1: one job per curve = every (start, gap ratio, frequency) run of that
# damper configuration, written as one CF netCDF dataset.


rule sweep_curve:
    output:
        "results/sweeps/{curve}.nc",
    log:
        "results/logs/sweep_curve/{curve}.log",
    benchmark:
        "results/benchmarks/sweep_curve/{curve}.tsv"
    wildcard_constraints:
        curve=f"({WALLED_KIND})_[A-Za-z0-9_.]+",
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=1000,
    params:
        library=library("sweep_curve"),
        study=curve_params,
    script:
        "../scripts/sweep_curve.py"


register(rules.sweep_curve, curve=list(CURVES))
