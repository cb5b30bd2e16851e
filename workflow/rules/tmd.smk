# The tuned mass damper reference: equal-peak (minimax) optimum and Den Hartog.


rule tmd_optimum:
    input:
        library=LIB_TMD,
    output:
        report(
            "results/tables/tmd_optimum.json",
            caption="../report/tmd_optimum.rst",
            category=snakemake_category("tmd_optimum"),
            subcategory=snakemake_subcategory("tmd_optimum"),
        ),
    params:
        mu=config["tmd"]["mu"],
        beta=config["structure"]["beta"],
        force_ratio=config["structure"]["force_ratio"],
    threads: 1
    resources:
        runtime=5, mem_mb=500,
    conda:
        ENV
    log:
        "results/logs/tmd_optimum.log",
    benchmark:
        "results/benchmarks/tmd_optimum.tsv"
    script:
        "../scripts/tmd_optimum.py"
