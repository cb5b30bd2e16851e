# The tuned mass damper reference: equal-peak (minimax) optimum and Den Hartog.


rule tmd_optimum:
    input:
        library=LIB_TMD,
    output:
        "results/tables/tmd_optimum.json",
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
