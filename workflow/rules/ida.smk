# Incremental dynamic analysis on the FEMA P695 suites: per building, the bare building (with every ground
# motion's Sa(T1)), then one job per damper type over the ladder; collected into one dataset, then the verdicts,
# the fragility fits and one figure per building.


rule ida_bare:
    output:
        "results/ida/runs/{building}/bare.nc",
    log:
        "results/logs/ida_bare/{building}.log",
    benchmark:
        "results/benchmarks/ida_bare/{building}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
    conda:
        ENV
    threads: 1
    resources:
        runtime=10,
        mem_mb=2000,
    params:
        library=library("ida_bare"),
        study=ida_bare_params,
    script:
        "../scripts/ida_bare.py"


rule ida_damper:
    input:
        bare=rules.ida_bare.output[0],
        design=ida_design,
    output:
        "results/ida/runs/{building}/{damper}.nc",
    log:
        "results/logs/ida_damper/{building}_{damper}.log",
    benchmark:
        "results/benchmarks/ida_damper/{building}_{damper}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
        damper=ANY_KIND,
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=2000,
    params:
        library=library("ida_damper"),
        study=ida_params,
    script:
        "../scripts/ida_damper.py"


rule ida_collect:
    input:
        bare=expand(rules.ida_bare.output[0], building=IDA_BUILDINGS),
        dampers=expand(rules.ida_damper.output[0], building=IDA_BUILDINGS, damper=IDA_KINDS),
    output:
        "results/ida/ida.nc",
    log:
        "results/logs/ida_collect.log",
    benchmark:
        "results/benchmarks/ida_collect.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=4000,
    params:
        library=library("ida_collect"),
    script:
        "../scripts/ida_collect.py"


rule ida_tables:
    input:
        dataset=rules.ida_collect.output[0],
    output:
        verdicts=report(
            "results/tables/ida_verdicts.csv",
            caption="../report/ida_verdicts.rst",
            category=SECTIONS["ida"],
            subcategory="Verdicts per record group",
        ),
        fragility=report(
            "results/tables/ida_fragility.csv",
            caption="../report/ida_fragility.rst",
            category=SECTIONS["ida"],
            subcategory="Probability of exceeding a drift ratio",
        ),
    log:
        "results/logs/ida_tables.log",
    benchmark:
        "results/benchmarks/ida_tables.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=2000,
    params:
        library=library("ida_tables"),
        study=lambda wildcards: IDA,
    script:
        "../scripts/ida_tables.py"


rule ida_figure:
    input:
        dataset=rules.ida_collect.output[0],
        fragility=rules.ida_tables.output.fragility,
    output:
        png=report(
            "results/figures/ida_{building}.png",
            caption="../report/ida_figure.rst",
            category=SECTIONS["ida"],
            subcategory=lambda wildcards: f"Building: {label(wildcards.building)}",
        ),
        pdf="results/figures/ida_{building}.pdf",
    log:
        "results/logs/ida_figure/{building}.log",
    benchmark:
        "results/benchmarks/ida_figure/{building}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=2000,
    params:
        library=library("ida_figure"),
        study=lambda wildcards: IDA,
    script:
        "../scripts/ida_figure.py"


if IDA:
    register(rules.ida_bare, building=IDA_BUILDINGS)
    register(rules.ida_damper, building=IDA_BUILDINGS, damper=IDA_KINDS)
    register(rules.ida_collect)
    register(rules.ida_tables, report=("verdicts", "fragility"))
    register(rules.ida_figure, report=("png",), building=IDA_BUILDINGS)
