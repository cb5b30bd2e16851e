# Stage 4: the self-contained HTML report, and the archive of the whole run.


rule report:
    input:
        # what the registry says the report shows (targets.smk), their captions and every registered
        # job's run time: a job that reruns updates its benchmark, and the report follows
        shown=lambda wildcards: [entry["path"] for entry in report_sections()],
        captions=report_captions(),
        overview=OVERVIEW,
        template=os.path.join(REPORT_DIR, "index.html.j2"),
        benchmarks=lambda wildcards: study_benchmarks(),
    output:
        REPORT,
    log:
        "results/logs/report.log",
    localrule: True
    conda:
        ENV
    threads: 1
    resources:
        runtime=5,
        mem_mb=1000,
        # a resource, not a param: shown in the report, but another executor reruns nothing
        executor=executor_name,
    params:
        library=library("report"),
        sections=lambda wildcards: report_sections(),
    script:
        "../scripts/report.py"


rule archive:
    input:
        products=lambda wildcards: study_outputs(),
        report=rules.report.output[0],
        config=[os.path.relpath(f) for f in workflow.configfiles],
    output:
        ARCHIVE,
    log:
        "results/logs/archive.log",
    localrule: True
    conda:
        ENV
    threads: 1
    resources:
        runtime=10,
        mem_mb=1000,
    params:
        library=library("archive"),
    script:
        "../scripts/archive.py"
