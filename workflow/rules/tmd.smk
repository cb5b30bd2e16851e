# The tuned mass damper reference: equal-peak (minimax) optimum and Den Hartog.


rule tmd_optimum:
    output:
        report(
            "results/tables/tmd_optimum.json",
            caption="../report/tmd_optimum.rst",
            category=SECTIONS["figures"],
            subcategory="The optimum tuned mass damper (Fig. 11's reference)",
        ),
    log:
        "results/logs/tmd_optimum.log",
    benchmark:
        "results/benchmarks/tmd_optimum.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=500,
    params:
        library=library("tmd_optimum"),
        mu=config["tmd"]["mu"],
        beta=config["structure"]["beta"],
        force_ratio=config["structure"]["force_ratio"],
    script:
        "../scripts/tmd_optimum.py"


register(rules.tmd_optimum, report=(0,))
