# Design charts: sweeps on the charts' frequency window -> one chart per damper
# (results/design/chart_<damper>.nc, which `impact design` reads) -> the figure; the design equations fitted
# on the charts and checked by direct sweeps (results/design/equations.json, which the package ships) -> theirs.


rule design_sweep:
    output:
        "results/design/sweeps/{curve}.nc",
    log:
        "results/logs/design_sweep/{curve}.log",
    benchmark:
        "results/benchmarks/design_sweep/{curve}.tsv"
    wildcard_constraints:
        curve=f"({WALLED_KIND})_[A-Za-z0-9_.]+",
    conda:
        ENV
    threads: 1
    resources:
        runtime=30,
        mem_mb=1000,
    params:
        library=library("design_sweep"),
        study=design_curve_params,
    script:
        "../scripts/design_sweep.py"


rule design_chart:
    input:
        sweeps=design_chart_sweeps,
    output:
        "results/design/chart_{kind}.nc",
    log:
        "results/logs/design_chart/{kind}.log",
    benchmark:
        "results/benchmarks/design_chart/{kind}.tsv"
    wildcard_constraints:
        kind=ANY_KIND,
    conda:
        ENV
    threads: 1
    resources:
        runtime=10,
        mem_mb=1000,
    params:
        library=library("design_chart"),
        study=lambda wildcards: design_chart_params(),
    script:
        "../scripts/design_chart.py"


rule design_figure:
    input:
        charts=expand(rules.design_chart.output[0], kind=DESIGN_KINDS),
    output:
        png=report(
            "results/figures/design_charts.png",
            caption="../report/design_charts.rst",
            category=SECTIONS["design"],
            subcategory="X_m charts for choosing mass, gap and tuning",
        ),
        pdf="results/figures/design_charts.pdf",
    log:
        "results/logs/design_figure.log",
    benchmark:
        "results/benchmarks/design_figure.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("design_figure"),
    script:
        "../scripts/design_figure.py"


rule design_equations:
    input:
        charts=expand(rules.design_chart.output[0], kind=IMPACT_KINDS),
    output:
        json="results/design/equations.json",
        checks="results/design/equations.nc",
    log:
        "results/logs/design_equations.log",
    benchmark:
        "results/benchmarks/design_equations.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=20,
        mem_mb=1000,
    params:
        library=library("design_equations"),
        study=lambda wildcards: {key: config[key] for key in ("structure", "protocol", "design")},
    script:
        "../scripts/design_equations.py"


rule design_equations_figure:
    input:
        checks=rules.design_equations.output.checks,
    output:
        png=report(
            "results/figures/design_equations.png",
            caption="../report/design_equations.rst",
            category=SECTIONS["design"],
            subcategory="Design equations against simulation",
        ),
        pdf="results/figures/design_equations.pdf",
    log:
        "results/logs/design_equations_figure.log",
    benchmark:
        "results/benchmarks/design_equations_figure.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("design_equations_figure"),
    script:
        "../scripts/design_equations_figure.py"


if DESIGN:
    register(rules.design_sweep, curve=[c for kind in DESIGN_CURVES.values() for c in kind])
    register(rules.design_chart, kind=DESIGN_KINDS)
    register(rules.design_figure, report=("png",))
    register(rules.design_equations)
    register(rules.design_equations_figure, report=("png",))
