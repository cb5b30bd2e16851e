# Earthquakes and wind on real buildings: the bare building per building, then one
# job per building and damper type, collected into one dataset per load family,
# then the tables, the reduction figure and one case in time.


rule loads_bare:
    output:
        "results/loads/runs/{building}/bare.nc",
    log:
        "results/logs/loads_bare/{building}.log",
    benchmark:
        "results/benchmarks/loads_bare/{building}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
    conda:
        ENV
    threads: 1
    resources:
        runtime=10,
        mem_mb=1000,
    params:
        library=library("loads_bare"),
        study=loads_params,
    script:
        "../scripts/loads_bare.py"


rule loads_damper:
    input:
        bare=rules.loads_bare.output[0],
    output:
        "results/loads/runs/{building}/{damper}.nc",
    log:
        "results/logs/loads_damper/{building}_{damper}.log",
    benchmark:
        "results/benchmarks/loads_damper/{building}_{damper}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
        damper=ANY_KIND,
    conda:
        ENV
    threads: 1
    resources:
        runtime=20,
        mem_mb=1000,
    params:
        library=library("loads_damper"),
        study=loads_params,
    script:
        "../scripts/loads_damper.py"


rule loads_collect:
    input:
        bare=expand(rules.loads_bare.output[0], building=LOADS_BUILDINGS),
        dampers=expand(rules.loads_damper.output[0], building=LOADS_BUILDINGS, damper=LOADS_KINDS),
    output:
        expand("results/loads/{family}.nc", family=LOADS_FAMILIES),
    log:
        "results/logs/loads_collect.log",
    benchmark:
        "results/benchmarks/loads_collect.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=2000,
    params:
        library=library("loads_collect"),
    script:
        "../scripts/loads_collect.py"


rule loads_tables:
    input:
        datasets=rules.loads_collect.output,
    output:
        best=report(
            "results/tables/loads_best_damper.csv",
            caption="../report/loads_best_damper.rst",
            category=SECTIONS["loads"],
            subcategory="The best damper per building and intensity",
        ),
        verdicts=report(
            "results/tables/loads_verdicts.csv",
            caption="../report/loads_verdicts.rst",
            category=SECTIONS["loads"],
            subcategory="Where each damper helps, does nothing or makes it worse",
        ),
    log:
        "results/logs/loads_tables.log",
    benchmark:
        "results/benchmarks/loads_tables.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("loads_tables"),
    script:
        "../scripts/loads_tables.py"


rule loads_figure:
    input:
        datasets=rules.loads_collect.output,
    output:
        png=report(
            "results/figures/loads_reduction.png",
            caption="../report/loads_reduction.rst",
            category=SECTIONS["loads"],
            subcategory="Response reduction against PGA",
        ),
        pdf="results/figures/loads_reduction.pdf",
    log:
        "results/logs/loads_figure.log",
    benchmark:
        "results/benchmarks/loads_figure.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("loads_figure"),
    script:
        "../scripts/loads_figure.py"


rule loads_time_history:
    input:
        bare=lambda wildcards: expand(rules.loads_bare.output[0], building=LOADS["time_history"]["building"]),
        damper=lambda wildcards: expand(
            rules.loads_damper.output[0],
            building=LOADS["time_history"]["building"],
            damper=LOADS["time_history"]["damper"],
        ),
    output:
        "results/loads/time_history.nc",
    log:
        "results/logs/loads_time_history.log",
    benchmark:
        "results/benchmarks/loads_time_history.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("loads_time_history"),
        study=lambda wildcards: LOADS,
    script:
        "../scripts/loads_time_history.py"


rule loads_time_history_figure:
    input:
        dataset=rules.loads_time_history.output[0],
    output:
        png=report(
            "results/figures/loads_time_history.png",
            caption="../report/loads_time_history.rst",
            category=SECTIONS["loads"],
            subcategory="One case in time",
        ),
        pdf="results/figures/loads_time_history.pdf",
    log:
        "results/logs/loads_time_history_figure.log",
    benchmark:
        "results/benchmarks/loads_time_history_figure.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("loads_time_history_figure"),
    script:
        "../scripts/loads_time_history_figure.py"


if LOADS:
    register(rules.loads_bare, building=LOADS_BUILDINGS)
    register(rules.loads_damper, building=LOADS_BUILDINGS, damper=LOADS_KINDS)
    register(rules.loads_collect)
    register(rules.loads_tables, report=("best", "verdicts"))
    register(rules.loads_figure, report=("png",))
    register(rules.loads_time_history)
    register(rules.loads_time_history_figure, report=("png",))
