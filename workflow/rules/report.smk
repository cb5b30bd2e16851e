# Stage 4: the self-contained HTML report, and the archive of the whole run.


rule report:
    input:
        figures=[
            *expand("results/figures/{fig}.png", fig=FIGURES),
            *[f for f in MASRI_OUTPUTS + COEXISTENCE_OUTPUTS if f.startswith("results/figures/")],
            *(["results/validation/fig3.png", "results/validation/fig5.png"] if VALIDATION else []),
            *(["results/figures/numerics_stability_map.png"] if NUMERICS_OUTPUTS else []),
        ],
        paper_vs_reproduced="results/tables/paper_vs_reproduced.csv",
        tmd_optimum="results/tables/tmd_optimum.json",
        masri_check=[f for f in MASRI_OUTPUTS if f.endswith("masri_check.csv")],
        masri_summary=[f for f in MASRI_OUTPUTS if f.endswith("masri_summary.json")],
        coexistence=[f for f in COEXISTENCE_OUTPUTS if f.endswith("coexistence.csv")],
        tables=(["results/tables/coexistence_e_trend.json"] if COEXISTENCE_CURVES else [])
        + (["results/validation/claims.json"] if VALIDATION else [])
        + (["results/tables/numerics_speed.csv"] if NUMERICS_OUTPUTS else []),
        cross_validation=VALIDATION_OUTPUTS,
        numerics_stability=[f for f in NUMERICS_OUTPUTS if f.endswith("numerics_stability.csv")],
        numerics_error_runtime=[f for f in NUMERICS_OUTPUTS if f.endswith("numerics_error_runtime.png")],
        # every job's run time: a job that reruns updates its benchmark, and the report follows
        benchmarks=report_benchmarks(),
        library=LIB_REPORT,
    output:
        "results/report/index.html",
    localrule: True
    threads: 1
    resources:
        runtime=5, mem_mb=1000,
        # a resource, not a param: shown in the report, but another executor reruns nothing
        executor=executor_name,
    conda:
        ENV
    log:
        "results/logs/report.log",
    script:
        "../scripts/build_report.py"


rule archive:
    input:
        sweeps=[sweep_file(spec) for spec in CURVES.values()],
        figures=expand("results/figures/{fig}.{ext}", fig=FIGURES, ext=("png", "pdf")),
        tables=["results/tables/paper_vs_reproduced.csv", "results/tables/tmd_optimum.json"],
        optional_stages=archive_extras(),
        report="results/report/index.html",
        config=[os.path.relpath(f) for f in workflow.configfiles],
        library=LIB_ARCHIVE,
    output:
        ARCHIVE,
    localrule: True
    threads: 1
    resources:
        runtime=10, mem_mb=1000,
    conda:
        ENV
    log:
        "results/logs/archive.log",
    script:
        "../scripts/build_archive.py"
