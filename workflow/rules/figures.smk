# Stage 2: figures from the datasets only; a style change reruns no simulation.


rule figure:
    input:
        curves=lambda wc: [sweep_file(s) for s in figure_curves(config, wc.fig).values()],
        tmd=lambda wc: rules.tmd_optimum.output if needs_tmd(wc.fig) else [],
    output:
        png=report(
            "results/figures/{fig}.png",
            caption="../report/figure.rst",
            category=SECTIONS["figures"],
            subcategory=lambda wc: figure_title(wc.fig),
        ),
        pdf="results/figures/{fig}.pdf",
    log:
        "results/logs/figure/{fig}.log",
    benchmark:
        "results/benchmarks/figure/{fig}.tsv"
    wildcard_constraints:
        fig="fig[0-9]{2}",
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("figure"),
        figure=lambda wc: config["figures"][wc.fig],
    script:
        "../scripts/figure.py"


register(rules.figure, report=("png",), fig=FIGURES)
