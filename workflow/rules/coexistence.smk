# Coexisting steady states of the CID: continuation sweeps, the initial-condition
# ensemble, and what they say about the paper's numbers.


rule continuation_curve:
    output:
        "results/coexistence/{curve}_{mode}.nc",
    log:
        "results/logs/continuation_curve/{curve}_{mode}.log",
    benchmark:
        "results/benchmarks/continuation_curve/{curve}_{mode}.tsv"
    wildcard_constraints:
        curve=CID_CURVE,
        mode="continuation_up|continuation_down",
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=1000,
    params:
        library=library("continuation_curve"),
        study=curve_params,
    script:
        "../scripts/continuation_curve.py"


rule ensemble_curve:
    output:
        "results/coexistence/{curve}_ensemble.nc",
    log:
        "results/logs/ensemble_curve/{curve}.log",
    benchmark:
        "results/benchmarks/ensemble_curve/{curve}.tsv"
    wildcard_constraints:
        curve=CID_CURVE,
    conda:
        ENV
    threads: 1
    resources:
        runtime=60,
        mem_mb=1000,
    params:
        library=library("ensemble_curve"),
        study=curve_params,
        ensemble=config.get("coexistence", {}).get("ensemble", {}),
    script:
        "../scripts/ensemble_curve.py"


rule coexistence_figure:
    input:
        from_rest=rules.sweep_curve.output[0],
        continuation=lambda wc: expand(rules.continuation_curve.output[0], curve=wc.curve, mode=COEXISTENCE_MODES),
        ensemble=rules.ensemble_curve.output[0],
    output:
        png=report(
            "results/figures/coexistence_{curve}.png",
            caption="../report/coexistence_figure.rst",
            category=SECTIONS["coexistence"],
            subcategory=lambda wildcards: f"Coexisting states of the {label(wildcards.curve)}",
        ),
        pdf="results/figures/coexistence_{curve}.pdf",
    log:
        "results/logs/coexistence_figure/{curve}.log",
    benchmark:
        "results/benchmarks/coexistence_figure/{curve}.tsv"
    wildcard_constraints:
        curve=CID_CURVE,
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("coexistence_figure"),
        spec=lambda wc: CURVES[wc.curve],
    script:
        "../scripts/coexistence_figure.py"


rule hysteresis_figure:
    input:
        from_rest=rules.sweep_curve.output[0],
        continuation=lambda wc: expand(rules.continuation_curve.output[0], curve=wc.curve, mode=COEXISTENCE_MODES),
    output:
        png=report(
            "results/figures/hysteresis_{curve}.png",
            caption="../report/hysteresis_figure.rst",
            category=SECTIONS["coexistence"],
            subcategory=lambda wildcards: f"Hysteresis of the {label(wildcards.curve)}",
        ),
        pdf="results/figures/hysteresis_{curve}.pdf",
    log:
        "results/logs/hysteresis_figure/{curve}.log",
    benchmark:
        "results/benchmarks/hysteresis_figure/{curve}.tsv"
    wildcard_constraints:
        curve=CID_CURVE,
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("hysteresis_figure"),
        spec=lambda wc: CURVES[wc.curve],
        gap_ratio=config.get("coexistence", {}).get("hysteresis", {}).get("gap_ratio", 1.6),
        structure=config["structure"],
    script:
        "../scripts/hysteresis_figure.py"


rule coexistence_table:
    input:
        from_rest=[sweep_file(s) for s in COEXISTENCE_CURVES],
        continuation=expand(
            rules.continuation_curve.output[0], curve=[curve_id(s) for s in COEXISTENCE_CURVES], mode=COEXISTENCE_MODES
        ),
        ensemble=expand(rules.ensemble_curve.output[0], curve=[curve_id(s) for s in COEXISTENCE_CURVES]),
    output:
        table=report(
            "results/tables/coexistence.csv",
            caption="../report/coexistence.rst",
            category=SECTIONS["coexistence"],
            subcategory="Coexisting steady states: table",
        ),
        statement=report(
            "results/tables/coexistence_e_trend.json",
            caption="../report/coexistence_e_trend.rst",
            category=SECTIONS["coexistence"],
            subcategory="The CID's e-trend across steady states",
        ),
    log:
        "results/logs/coexistence_table.log",
    benchmark:
        "results/benchmarks/coexistence_table.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("coexistence_table"),
    script:
        "../scripts/coexistence_table.py"


COEXISTENCE_IDS = [curve_id(s) for s in COEXISTENCE_CURVES]
register(rules.continuation_curve, curve=COEXISTENCE_IDS, mode=COEXISTENCE_MODES)
register(rules.ensemble_curve, curve=COEXISTENCE_IDS)
register(rules.coexistence_figure, report=("png",), curve=COEXISTENCE_IDS)
register(rules.hysteresis_figure, report=("png",), curve=COEXISTENCE_IDS)
if COEXISTENCE_CURVES:
    register(rules.coexistence_table, report=("table", "statement"))
