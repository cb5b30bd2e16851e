# Cross-validation against the experiment (Figs. 3-5): the model of Eq. 4 and a
# higher-fidelity virtual test rig, through the same analysis code as real records.


rule cross_validation:
    input:
        rig_config=VALIDATION.get("config", "config/validation.yaml"),
        library=LIB_CORE
        + library("core/sampler.py")
        + library(*(f"experiment/{m}.py" for m in ("__init__", "records", "analysis", "rig", "validation"))),
    output:
        table=report(
            "results/validation/validation_table.csv",
            caption="../report/cross_validation.rst",
            category="3. Experiment (cross-validation)",
            subcategory="Model against the virtual rig",
        ),
        curves="results/validation/validation_curves.csv",
        delta="results/validation/validation_delta.csv",
        drop_tests="results/validation/drop_tests.csv",
        claims="results/validation/claims.json",
        fig3="results/validation/fig3.png",
        fig3_pdf="results/validation/fig3.pdf",
        fig5="results/validation/fig5.png",
        fig5_pdf="results/validation/fig5.pdf",
    log:
        "results/logs/cross_validation.log",
    benchmark:
        "results/benchmarks/cross_validation.tsv"
    conda:
        ENV
    threads: VALIDATION.get("threads", 2)
    resources:
        runtime=30,
        mem_mb=2000,
    params:
        smoke=VALIDATION.get("smoke", False),
    script:
        "../scripts/cross_validation.py"


if VALIDATION:
    register(rules.cross_validation, report=("table", "claims", "fig3", "fig5"))
