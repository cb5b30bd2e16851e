# Stage 3: the paper's reported values beside ours.


def table_curves(wildcards):
    wanted = {curve_id(s) for s in comparison.needed_curves()}
    return [sweep_file(spec) for cid, spec in CURVES.items() if cid in wanted]


rule paper_vs_reproduced:
    input:
        curves=table_curves,
        tmd="results/tables/tmd_optimum.json",
        library=LIB_TABLE,
    output:
        "results/tables/paper_vs_reproduced.csv",
    log:
        "results/logs/paper_vs_reproduced.log",
    benchmark:
        "results/benchmarks/paper_vs_reproduced.tsv"
    script:
        "../scripts/paper_vs_reproduced.py"
