# The closed-form check: Masri's 2-EIPC orbit and its stability against the
# simulator (on the orbit, perturbed off it, and from rest).


rule masri_check:
    input:
        library=LIB_CORE + library("masri.py", "masri_check.py"),
    output:
        dataset="results/checks/masri.nc",
        table="results/tables/masri_check.csv",
        summary="results/checks/masri_summary.json",
    params:
        grid=config["masri"]["grid"],
        structure=config["structure"],
        protocol={k: config["protocol"][k] for k in ("periods", "average_from")},
        starts=config["protocol"]["starts"]["cid"],
    threads: 1
    resources:
        runtime=30, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/masri_check.log",
    benchmark:
        "results/benchmarks/masri_check.tsv"
    script:
        "../scripts/masri_check.py"


rule masri_chart:
    input:
        library=library("masri.py", "masri_check.py", "params.py"),
    output:
        "results/checks/masri_chart.nc",
    params:
        chart=config["masri"]["chart"],
        structure=config["structure"],
    threads: 1
    resources:
        runtime=30, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/masri_chart.log",
    benchmark:
        "results/benchmarks/masri_chart.tsv"
    script:
        "../scripts/masri_chart.py"


rule masri_branches:
    input:
        library=LIB_CORE + library("masri.py", "masri_check.py"),
    output:
        "results/checks/masri_branches.nc",
    params:
        branches=config["masri"]["branches"],
        structure=config["structure"],
        protocol={k: config["protocol"][k] for k in ("periods", "average_from")},
        starts=config["protocol"]["starts"]["cid"],
    threads: 1
    resources:
        runtime=30, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/masri_branches.log",
    benchmark:
        "results/benchmarks/masri_branches.tsv"
    script:
        "../scripts/masri_branches.py"


rule masri_figures:
    input:
        chart="results/checks/masri_chart.nc",
        branches="results/checks/masri_branches.nc",
        library=LIB_PLOT,
    output:
        chart_png="results/figures/masri_stability.png",
        chart_pdf="results/figures/masri_stability.pdf",
        branches_png="results/figures/masri_branches.png",
        branches_pdf="results/figures/masri_branches.pdf",
    threads: 1
    resources:
        runtime=5, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/masri_figures.log",
    benchmark:
        "results/benchmarks/masri_figures.tsv"
    script:
        "../scripts/plot_masri.py"
