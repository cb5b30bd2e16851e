# The impact-damper study: parameters -> sweeps -> datasets -> figures -> tables.
# Thin on purpose: configuration, its validation and the stage includes.
# The physics lives in src/impact; each stage's rules in workflow/rules/.
from snakemake.utils import min_version, validate

min_version("9.0")


# the paper's study unless a --configfile is given (a partial merge of two
# studies would silently mix their figures)
if not config:

    configfile: "config/config.yaml"



validate(config, "workflow/schemas/config.schema.yaml")


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/sweeps.smk"
include: "workflow/rules/tmd.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/tables.smk"
include: "workflow/rules/report.smk"
include: "workflow/rules/masri.smk"
include: "workflow/rules/coexistence.smk"
include: "workflow/rules/validation.smk"
include: "workflow/rules/numerics.smk"


rule all:
    default_target: True
    input:
        figures=expand("results/figures/{fig}.{ext}", fig=FIGURES, ext=("png", "pdf")),
        table="results/tables/paper_vs_reproduced.csv",
        report="results/report/index.html",
        masri=MASRI_OUTPUTS,
        coexistence=COEXISTENCE_OUTPUTS,
        validation=VALIDATION_OUTPUTS,
        numerics=NUMERICS_OUTPUTS,
