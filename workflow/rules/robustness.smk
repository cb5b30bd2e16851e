# Table 1 of the paper in numbers: each damper at its design point (from the
# sweeps and the TMD optimum), then X_m as the load, the structure, the damper's
# damping and e change; one job per design, then the table and the figure.


rule robustness_designs:
    input:
        sweeps=robustness_sweeps,
        tmd=rules.tmd_optimum.output[0],
    output:
        "results/robustness/designs.json",
    log:
        "results/logs/robustness_designs.log",
    benchmark:
        "results/benchmarks/robustness_designs.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("robustness_designs"),
        study=robustness_params,
    script:
        "../scripts/robustness_designs.py"


rule robustness_design:
    input:
        designs=rules.robustness_designs.output[0],
    output:
        "results/robustness/{design}.nc",
    log:
        "results/logs/robustness_design/{design}.log",
    benchmark:
        "results/benchmarks/robustness_design/{design}.tsv"
    wildcard_constraints:
        design=f"({ANY_KIND})[A-Za-z0-9_.]*",
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=1000,
    params:
        library=library("robustness_design"),
        study=robustness_params,
    script:
        "../scripts/robustness_design.py"


rule robustness_table:
    input:
        designs=expand(rules.robustness_design.output[0], design=ROBUSTNESS_DESIGNS),
    output:
        report(
            "results/tables/table1_measured.csv",
            caption="../report/table1_measured.rst",
            category=SECTIONS["robustness"],
            subcategory="The paper's Table 1, measured",
        ),
    log:
        "results/logs/robustness_table.log",
    benchmark:
        "results/benchmarks/robustness_table.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("robustness_table"),
    script:
        "../scripts/robustness_table.py"


rule robustness_figure:
    input:
        designs=expand(rules.robustness_design.output[0], design=ROBUSTNESS_DESIGNS),
    output:
        png=report(
            "results/figures/robustness.png",
            caption="../report/robustness.rst",
            category=SECTIONS["robustness"],
            subcategory="X_m as conditions change",
        ),
        pdf="results/figures/robustness.pdf",
    log:
        "results/logs/robustness_figure.log",
    benchmark:
        "results/benchmarks/robustness_figure.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("robustness_figure"),
    script:
        "../scripts/robustness_figure.py"


if ROBUSTNESS:
    register(rules.robustness_designs)
    register(rules.robustness_design, design=ROBUSTNESS_DESIGNS)
    register(rules.robustness_table, report=(0,))
    register(rules.robustness_figure, report=("png",))
