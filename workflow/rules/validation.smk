# Cross-validation against the experiment (Figs. 3-5): the model of Eq. 4 against a
# higher-fidelity virtual test rig, through the same analysis code as real records.
# One job per wall material, each running every case of the paper's grid on that wall (its own file
# and log line each), then the grid's tables, the drop tests, the data of Figs. 3 and 5, the claims and
# the figures.  Everything here is synthetic.


rule validation_contact_laws:
    input:
        rig_config=RIG_FILE,
    output:
        "results/validation/contact_laws.json",
    log:
        "results/logs/validation_contact_laws.log",
    benchmark:
        "results/benchmarks/validation_contact_laws.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("validation_contact_laws"),
        rig=RIG,
    script:
        "../scripts/validation_contact_laws.py"


rule validation_cases:
    input:
        rig_config=RIG_FILE,
        contact_laws=rules.validation_contact_laws.output[0],
    output:
        expand("results/validation/cases/{setup}_{{wall}}.json", setup=RIG_SETUPS),
    log:
        "results/logs/validation_cases/{wall}.log",
    benchmark:
        "results/benchmarks/validation_cases/{wall}.tsv"
    wildcard_constraints:
        wall="|".join(re.escape(wall) for wall in RIG_WALLS) or "none",
    conda:
        ENV
    threads: 1
    resources:
        runtime=60,
        mem_mb=1000,
    params:
        library=library("validation_cases"),
        rig=RIG,
        cases=lambda wc: [RIG_CASES[f"{setup}_{wc.wall}"] for setup in RIG_SETUPS],
    script:
        "../scripts/validation_cases.py"


rule validation_grid:
    input:
        cases=expand(rules.validation_cases.output, wall=RIG_WALLS),
    output:
        table=report(
            "results/validation/validation_table.csv",
            caption="../report/cross_validation.rst",
            category=SECTIONS["validation"],
            subcategory="Model against the virtual rig",
        ),
        curves="results/validation/validation_curves.csv",
        delta="results/validation/validation_delta.csv",
    log:
        "results/logs/validation_grid.log",
    benchmark:
        "results/benchmarks/validation_grid.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("validation_grid"),
    script:
        "../scripts/validation_grid.py"


rule validation_drop_tests:
    input:
        rig_config=RIG_FILE,
        contact_laws=rules.validation_contact_laws.output[0],
    output:
        table="results/validation/drop_tests.csv",
        records=directory("results/validation/records/drop_tests"),
    log:
        "results/logs/validation_drop_tests.log",
    benchmark:
        "results/benchmarks/validation_drop_tests.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("validation_drop_tests"),
        rig=RIG,
    script:
        "../scripts/validation_drop_tests.py"


rule validation_fig3_data:
    input:
        rig_config=RIG_FILE,
        contact_laws=rules.validation_contact_laws.output[0],
    output:
        data="results/validation/fig3_data.json",
        decay="results/validation/fig3a_decay.csv",
        sweep="results/validation/fig3b_sweep.csv",
        fig3a=directory("results/validation/records/fig3a"),
        fig3b_paper_grid=directory("results/validation/records/fig3b_paper_grid"),
        fig3b_fine_grid=directory("results/validation/records/fig3b_fine_grid"),
    log:
        "results/logs/validation_fig3_data.log",
    benchmark:
        "results/benchmarks/validation_fig3_data.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=10,
        mem_mb=1000,
    params:
        library=library("validation_figure_data"),
        rig=RIG,
    script:
        "../scripts/validation_figure_data.py"


rule validation_fig5_data:
    input:
        rig_config=RIG_FILE,
        contact_laws=rules.validation_contact_laws.output[0],
    output:
        data="results/validation/fig5_data.json",
        decay="results/validation/fig5a_decay.csv",
        sweep="results/validation/fig5b_sweep.csv",
        fig5a_pid=directory("results/validation/records/fig5a_pid"),
        fig5a_bare=directory("results/validation/records/fig5a_bare"),
        fig5b=directory("results/validation/records/fig5b"),
    log:
        "results/logs/validation_fig5_data.log",
    benchmark:
        "results/benchmarks/validation_fig5_data.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=10,
        mem_mb=1000,
    params:
        library=library("validation_figure_data"),
        rig=RIG,
    script:
        "../scripts/validation_figure_data.py"


rule validation_claims:
    input:
        table=rules.validation_grid.output.table,
        curves=rules.validation_grid.output.curves,
        fig3=rules.validation_fig3_data.output.data,
        fig5=rules.validation_fig5_data.output.data,
        drop_tests=rules.validation_drop_tests.output.table,
    output:
        report(
            "results/validation/claims.json",
            caption="../report/validation_claims.rst",
            category=SECTIONS["validation"],
            subcategory="The paper's Section 3 claims",
        ),
    log:
        "results/logs/validation_claims.log",
    benchmark:
        "results/benchmarks/validation_claims.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("validation_claims"),
        rig=RIG,
        smoke=VALIDATION.get("smoke", False),
    script:
        "../scripts/validation_claims.py"


rule validation_figures:
    input:
        fig3=rules.validation_fig3_data.output.data,
        fig5=rules.validation_fig5_data.output.data,
    output:
        fig3=report(
            "results/validation/fig3.png",
            caption="../report/validation_fig3.rst",
            category=SECTIONS["validation"],
            subcategory="Fig. 3: the bare structure",
        ),
        fig3_pdf="results/validation/fig3.pdf",
        fig5=report(
            "results/validation/fig5.png",
            caption="../report/validation_fig5.rst",
            category=SECTIONS["validation"],
            subcategory="Fig. 5: the PID",
        ),
        fig5_pdf="results/validation/fig5.pdf",
        histories="results/validation/fig4_histories.png",
    log:
        "results/logs/validation_figures.log",
    benchmark:
        "results/benchmarks/validation_figures.tsv"
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
    params:
        library=library("validation_figures"),
    script:
        "../scripts/validation_figures.py"


if VALIDATION:
    register(rules.validation_contact_laws)
    register(rules.validation_cases, wall=RIG_WALLS)
    register(rules.validation_grid, report=("table",))
    register(rules.validation_drop_tests)
    register(rules.validation_fig3_data)
    register(rules.validation_fig5_data)
    register(rules.validation_claims, report=(0,))
    register(rules.validation_figures, report=("fig3", "fig5"))
