# The closed-form check: Masri's 2-EIPC orbit and its stability against the
# simulator (on the orbit, perturbed off it, and from rest).


rule masri_check:
    output:
        dataset="results/checks/masri.nc",
        table=report(
            "results/tables/masri_check.csv",
            caption="../report/masri_check.rst",
            category=SECTIONS["masri"],
            subcategory="The simulator against the closed form, point by point",
        ),
        summary=report(
            "results/checks/masri_summary.json",
            caption="../report/masri_summary.rst",
            category=SECTIONS["masri"],
            subcategory="Summary of the closed-form check",
        ),
    log:
        "results/logs/masri_check.log",
    benchmark:
        "results/benchmarks/masri_check.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=1000,
    params:
        library=library("masri_check"),
        grid=config["masri"]["grid"],
        structure=config["structure"],
        protocol={k: config["protocol"][k] for k in ("periods", "average_from")},
        starts=config["protocol"]["starts"][CID],
    script:
        "../scripts/masri_check.py"


rule masri_chart:
    output:
        "results/checks/masri_chart.nc",
    log:
        "results/logs/masri_chart.log",
    benchmark:
        "results/benchmarks/masri_chart.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=1000,
    params:
        library=library("masri_chart"),
        chart=config["masri"]["chart"],
        structure=config["structure"],
    script:
        "../scripts/masri_chart.py"


rule masri_branches:
    output:
        "results/checks/masri_branches.nc",
    log:
        "results/logs/masri_branches.log",
    benchmark:
        "results/benchmarks/masri_branches.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=1000,
    params:
        library=library("masri_branches"),
        branches=config["masri"]["branches"],
        structure=config["structure"],
        protocol={k: config["protocol"][k] for k in ("periods", "average_from")},
        starts=config["protocol"]["starts"][CID],
    script:
        "../scripts/masri_branches.py"


rule masri_figures:
    input:
        chart=rules.masri_chart.output[0],
        branches=rules.masri_branches.output[0],
    output:
        chart_png=report(
            "results/figures/masri_stability.png",
            caption="../report/masri_stability.rst",
            category=SECTIONS["masri"],
            subcategory="Where the 2-EIPC orbit exists and is stable",
        ),
        chart_pdf="results/figures/masri_stability.pdf",
        branches_png=report(
            "results/figures/masri_branches.png",
            caption="../report/masri_branches.rst",
            category=SECTIONS["masri"],
            subcategory="Branches and runs from rest",
        ),
        branches_pdf="results/figures/masri_branches.pdf",
    log:
        "results/logs/masri_figures.log",
    benchmark:
        "results/benchmarks/masri_figures.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("masri_figures"),
    script:
        "../scripts/masri_figures.py"


if MASRI:
    register(rules.masri_check, report=("table", "summary"))
    register(rules.masri_chart)
    register(rules.masri_branches)
    register(rules.masri_figures, report=("chart_png", "branches_png"))
