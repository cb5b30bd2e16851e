# The closed-form check: Masri's 2-EIPC orbit and its stability against the
# simulator (on the orbit, perturbed off it, and from rest).


rule masri_check:
    input:
        library=LIB_CORE + library("masri.py", "masri_check.py"),
    output:
        dataset="results/checks/masri.nc",
        table=report(
            "results/tables/masri_check.csv",
            caption="../report/masri_check.rst",
            category=snakemake_category("masri_check"),
            subcategory=snakemake_subcategory("masri_check"),
        ),
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
        chart_png=report(
            "results/figures/masri_stability.png",
            caption="../report/masri_stability.rst",
            category=snakemake_category("masri_stability"),
            subcategory=snakemake_subcategory("masri_stability"),
        ),
        chart_pdf="results/figures/masri_stability.pdf",
        branches_png=report(
            "results/figures/masri_branches.png",
            caption="../report/masri_branches.rst",
            category=snakemake_category("masri_branches"),
            subcategory=snakemake_subcategory("masri_branches"),
        ),
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
