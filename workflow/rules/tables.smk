# Stage 3: the paper's reported values beside ours.


rule paper_vs_reproduced:
    input:
        curves=table_curves,
        tmd=rules.tmd_optimum.output[0],
    output:
        report(
            "results/tables/paper_vs_reproduced.csv",
            caption="../report/paper_vs_reproduced.rst",
            category=SECTIONS["paper"],
            subcategory="The paper's reported values beside ours",
        ),
    log:
        "results/logs/paper_vs_reproduced.log",
    benchmark:
        "results/benchmarks/paper_vs_reproduced.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("paper_vs_reproduced"),
    script:
        "../scripts/paper_vs_reproduced.py"


register(rules.paper_vs_reproduced, report=(0,))
