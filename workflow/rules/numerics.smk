# Numerics shown, not assumed: every integrator's error against its run time,
# and stability on stiff and extreme cases.  One job per (case, method family)
# for the work-precision runs and one per family for the extreme cases, each run
# within the configured budget; then the dataset, the tables and the figures.


rule numerics_work_precision_piece:
    output:
        "results/numerics/work_precision/{case}/{family}.nc",
    log:
        "results/logs/numerics_work_precision/{case}/{family}.log",
    benchmark:
        "results/benchmarks/numerics_work_precision/{case}/{family}.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=2000,
    params:
        library=library("numerics_work_precision_piece"),
        numerics=config.get("numerics", {}),
    script:
        "../scripts/numerics_work_precision_piece.py"


rule numerics_work_precision:
    input:
        pieces=[
            expand(rules.numerics_work_precision_piece.output[0], case=case, family=fam)[0]
            for case, fam in NUMERICS_PIECES
        ],
    output:
        dataset="results/numerics/work_precision.nc",
        speed=report(
            "results/tables/numerics_speed.csv",
            caption="../report/numerics_speed.rst",
            category=SECTIONS["numerics"],
            subcategory="Speed at equal error",
        ),
    log:
        "results/logs/numerics_work_precision.log",
    benchmark:
        "results/benchmarks/numerics_work_precision.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=2000,
    params:
        library=library("numerics_work_precision"),
        numerics=config.get("numerics", {}),
    script:
        "../scripts/numerics_work_precision.py"


rule numerics_stability_piece:
    output:
        "results/numerics/stability/{family}.csv",
    log:
        "results/logs/numerics_stability/{family}.log",
    benchmark:
        "results/benchmarks/numerics_stability/{family}.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=2000,
    params:
        library=library("numerics_stability_piece"),
        numerics=config.get("numerics", {}),
    script:
        "../scripts/numerics_stability_piece.py"


rule numerics_stability:
    input:
        pieces=expand(rules.numerics_stability_piece.output[0], family=STABILITY_FAMILIES),
    output:
        table=report(
            "results/tables/numerics_stability.csv",
            caption="../report/numerics_stability.rst",
            category=SECTIONS["numerics"],
            subcategory="Stability on extreme cases",
        ),
    log:
        "results/logs/numerics_stability.log",
    benchmark:
        "results/benchmarks/numerics_stability.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=2000,
    params:
        library=library("numerics_stability"),
        numerics=config.get("numerics", {}),
    script:
        "../scripts/numerics_stability.py"


rule numerics_figures:
    input:
        dataset=rules.numerics_work_precision.output.dataset,
        stability=rules.numerics_stability.output.table,
    output:
        work_png=report(
            "results/figures/numerics_error_runtime.png",
            caption="../report/numerics_error_runtime.rst",
            category=SECTIONS["numerics"],
            subcategory="Error against run time",
        ),
        work_pdf="results/figures/numerics_error_runtime.pdf",
        map_png=report(
            "results/figures/numerics_stability_map.png",
            caption="../report/numerics_stability_map.rst",
            category=SECTIONS["numerics"],
            subcategory="Stability map",
        ),
        map_pdf="results/figures/numerics_stability_map.pdf",
    log:
        "results/logs/numerics_figures.log",
    benchmark:
        "results/benchmarks/numerics_figures.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("numerics_figures"),
    script:
        "../scripts/numerics_figures.py"


if NUMERICS:
    for case, fam in NUMERICS_PIECES:
        register(rules.numerics_work_precision_piece, case=[case], family=[fam])
    register(rules.numerics_stability_piece, family=STABILITY_FAMILIES)
    register(rules.numerics_work_precision, report=("speed",))
    register(rules.numerics_stability, report=("table",))
    register(rules.numerics_figures, report=("map_png", "work_png"))
