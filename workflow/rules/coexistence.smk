# Coexisting steady states of the CID: continuation sweeps, the initial-condition
# ensemble, and what they say about the paper's numbers.


rule continuation_curve:
    input:
        library=LIB_SWEEP,
    output:
        "results/coexistence/{curve}_{mode}.nc",
    params:
        study=curve_params,
    threads: 1
    resources:
        runtime=30, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/continuation_curve/{curve}_{mode}.log",
    benchmark:
        "results/benchmarks/continuation_curve/{curve}_{mode}.tsv"
    wildcard_constraints:
        curve="cid_[A-Za-z0-9_.]+",
        mode="continuation_up|continuation_down",
    script:
        "../scripts/continuation_curve.py"


rule ensemble_curve:
    input:
        library=LIB_SWEEP + library("coexistence.py"),
    output:
        "results/coexistence/{curve}_ensemble.nc",
    params:
        study=curve_params,
        ensemble=config.get("coexistence", {}).get("ensemble", {}),
    threads: 1
    resources:
        runtime=60, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/ensemble_curve/{curve}.log",
    benchmark:
        "results/benchmarks/ensemble_curve/{curve}.tsv"
    wildcard_constraints:
        curve="cid_[A-Za-z0-9_.]+",
    script:
        "../scripts/ensemble_curve.py"


rule coexistence_figure:
    input:
        from_rest="results/sweeps/{curve}.nc",
        continuation=lambda wc: [f"results/coexistence/{wc.curve}_{m}.nc" for m in COEXISTENCE_MODES],
        ensemble="results/coexistence/{curve}_ensemble.nc",
        library=LIB_PLOT,
    output:
        png=report(
            "results/figures/coexistence_{curve}.png",
            caption="../report/coexistence_figure.rst",
            category=snakemake_category("coexistence_"),
            subcategory=snakemake_subcategory("coexistence_"),
        ),
        pdf="results/figures/coexistence_{curve}.pdf",
    params:
        spec=lambda wc: CURVES[wc.curve],
    threads: 1
    resources:
        runtime=5, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/coexistence_figure/{curve}.log",
    benchmark:
        "results/benchmarks/coexistence_figure/{curve}.tsv"
    wildcard_constraints:
        curve="cid_[A-Za-z0-9_.]+",
    script:
        "../scripts/plot_coexistence.py"


rule hysteresis_figure:
    input:
        from_rest="results/sweeps/{curve}.nc",
        continuation=lambda wc: [f"results/coexistence/{wc.curve}_{m}.nc" for m in COEXISTENCE_MODES],
        library=LIB_PLOT + library("masri.py", "masri_check.py"),
    output:
        png=report(
            "results/figures/hysteresis_{curve}.png",
            caption="../report/hysteresis_figure.rst",
            category=snakemake_category("hysteresis_"),
            subcategory=snakemake_subcategory("hysteresis_"),
        ),
        pdf="results/figures/hysteresis_{curve}.pdf",
    params:
        spec=lambda wc: CURVES[wc.curve],
        gap_ratio=config.get("coexistence", {}).get("hysteresis", {}).get("gap_ratio", 1.6),
        structure=config["structure"],
    threads: 1
    resources:
        runtime=5, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/hysteresis_figure/{curve}.log",
    benchmark:
        "results/benchmarks/hysteresis_figure/{curve}.tsv"
    wildcard_constraints:
        curve="cid_[A-Za-z0-9_.]+",
    script:
        "../scripts/plot_hysteresis.py"


rule coexistence_table:
    input:
        from_rest=[sweep_file(s) for s in COEXISTENCE_CURVES],
        continuation=[f"results/coexistence/{curve_id(s)}_{m}.nc" for s in COEXISTENCE_CURVES for m in COEXISTENCE_MODES],
        ensemble=[f"results/coexistence/{curve_id(s)}_ensemble.nc" for s in COEXISTENCE_CURVES],
        library=library("comparison.py", "study.py", "pipeline.py"),
    output:
        table=report(
            "results/tables/coexistence.csv",
            caption="../report/coexistence.rst",
            category=snakemake_category("coexistence"),
            subcategory=snakemake_subcategory("coexistence"),
        ),
        statement="results/tables/coexistence_e_trend.json",
    threads: 1
    resources:
        runtime=5, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/coexistence_table.log",
    benchmark:
        "results/benchmarks/coexistence_table.tsv"
    script:
        "../scripts/coexistence_table.py"
