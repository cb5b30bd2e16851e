# Collapse on the FEMA P695 suites: per building made to yield, the bare archetype (its design and pushover) and
# each damper type traced to collapse, motion by motion; then the collapse margins, the verdicts and one figure per
# archetype.


rule collapse_bare:
    input:
        ida_bare=rules.ida_bare.output[0],
    output:
        "results/collapse/runs/{building}/bare.nc",
    log:
        "results/logs/collapse_bare/{building}.log",
    benchmark:
        "results/benchmarks/collapse_bare/{building}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=2000,
    params:
        library=library("collapse_bare"),
        study=collapse_bare_params,
    script:
        "../scripts/collapse_bare.py"


rule collapse_damper:
    input:
        ida_bare=rules.ida_bare.output[0],
        design=ida_design,
        bare=rules.collapse_bare.output[0],
    output:
        "results/collapse/runs/{building}/{damper}.nc",
    log:
        "results/logs/collapse_damper/{building}_{damper}.log",
    benchmark:
        "results/benchmarks/collapse_damper/{building}_{damper}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
        damper=ANY_KIND,
    conda:
        ENV
    threads: 1
    resources:
        runtime=60,
        mem_mb=2000,
    params:
        library=library("collapse_damper"),
        study=collapse_params,
    script:
        "../scripts/collapse_damper.py"


rule collapse_tables:
    input:
        bare=expand(rules.collapse_bare.output[0], building=COLLAPSE_BUILDINGS),
        dampers=expand(rules.collapse_damper.output[0], building=COLLAPSE_BUILDINGS, damper=IDA_KINDS),
    output:
        margins=report(
            "results/tables/collapse_margins.csv",
            caption="../report/collapse_margins.rst",
            category=SECTIONS["collapse"],
            subcategory="Collapse margins",
        ),
        verdicts=report(
            "results/tables/collapse_verdicts.csv",
            caption="../report/collapse_verdicts.rst",
            category=SECTIONS["collapse"],
            subcategory="Each damper against the bare archetype",
        ),
        best=report(
            "results/tables/collapse_best.csv",
            caption="../report/collapse_best.rst",
            category=SECTIONS["collapse"],
            subcategory="Verdicts",
        ),
        groups=report(
            "results/tables/collapse_groups.csv",
            caption="../report/collapse_groups.rst",
            category=SECTIONS["collapse"],
            subcategory="The archetypes as a performance group",
        ),
        summary="results/tables/collapse_summary.md",
    log:
        "results/logs/collapse_tables.log",
    benchmark:
        "results/benchmarks/collapse_tables.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=2000,
    params:
        library=library("collapse_tables"),
        study=lambda wildcards: COLLAPSE,
    script:
        "../scripts/collapse_tables.py"


rule collapse_figure:
    input:
        bare=rules.collapse_bare.output[0],
        dampers=expand(rules.collapse_damper.output[0], damper=IDA_KINDS, allow_missing=True),
    output:
        png=report(
            "results/figures/collapse_{building}.png",
            caption="../report/collapse_figure.rst",
            category=SECTIONS["collapse"],
            subcategory=lambda wildcards: f"Archetype: {label(wildcards.building)}",
        ),
        pdf="results/figures/collapse_{building}.pdf",
    log:
        "results/logs/collapse_figure/{building}.log",
    benchmark:
        "results/benchmarks/collapse_figure/{building}.tsv"
    wildcard_constraints:
        building=BUILDING_IDS,
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=2000,
    params:
        library=library("collapse_figure"),
    script:
        "../scripts/collapse_figure.py"


if COLLAPSE:
    register(rules.collapse_bare, building=COLLAPSE_BUILDINGS)
    register(rules.collapse_damper, building=COLLAPSE_BUILDINGS, damper=IDA_KINDS)
    register(rules.collapse_tables, report=("best", "groups", "margins", "verdicts"))
    register(rules.collapse_figure, report=("png",), building=COLLAPSE_BUILDINGS)
