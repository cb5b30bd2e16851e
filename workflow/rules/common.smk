# Shared helpers: the study's curves from the configuration, library sources
# as rule inputs (Snakemake does not track what a script imports).
import os

from impact import comparison
from impact.archive import archive_name
from impact.provenance import git_state
from impact.report import snakemake_category, snakemake_subcategory
from impact.study import all_curves, check_config, curve_id, figure_curves, friction_scale

check_config(config)

FIGURES = list(config["figures"])
CURVES = all_curves(config)

ENV = "../envs/impact.yaml"


def library(*names):
    """Library source files a rule's script imports, as its inputs."""
    return [os.path.join("src", "impact", name) for name in names]


# the paper kernel shares its contact search (and so these modules) with the scene core
LIB_CORE = library("__init__.py", "params.py", "_kernels.py", "simulate.py", "provenance.py", "pipeline.py",
                   "core/__init__.py", "core/events.py", "core/segment.py", "core/layout.py", "core/jitcache.py")
LIB_SWEEP = LIB_CORE + library("dataset.py", "study.py")
LIB_TMD = library("tmd.py", "pipeline.py", "params.py")
LIB_PLOT = library("plotting.py", "study.py", "pipeline.py")
LIB_TABLE = library("comparison.py", "study.py", "pipeline.py")
LIB_REPORT = library("report.py", "provenance.py", "pipeline.py")
LIB_ARCHIVE = library("archive.py", "report.py", "provenance.py", "pipeline.py")

# one archive per commit, "-dirty" when the source tree has uncommitted changes
ARCHIVE = f"results/archive/{archive_name(git_state()['git_commit'], git_state()['git_dirty'])}"


# stages that run only when configured
MASRI_OUTPUTS = (
    [
        "results/tables/masri_check.csv",
        "results/checks/masri_summary.json",
        "results/figures/masri_stability.png",
        "results/figures/masri_branches.png",
    ]
    if "masri" in config
    else []
)


NUMERICS_OUTPUTS = (
    ["results/figures/numerics_error_runtime.png", "results/tables/numerics_stability.csv",
     "results/tables/numerics_speed.csv"]
    if "numerics" in config
    else []
)

VALIDATION = config.get("validation", {})
VALIDATION_OUTPUTS = ["results/validation/validation_table.csv"] if VALIDATION else []

COEXISTENCE_CURVES = config.get("coexistence", {}).get("curves", [])
COEXISTENCE_MODES = config.get("coexistence", {}).get("modes", ["continuation_up", "continuation_down"])
COEXISTENCE_OUTPUTS = (
    ["results/tables/coexistence.csv"]
    + [f"results/figures/coexistence_{curve_id(s)}.png" for s in COEXISTENCE_CURVES]
    + [f"results/figures/hysteresis_{curve_id(s)}.png" for s in COEXISTENCE_CURVES]
    if COEXISTENCE_CURVES
    else []
)


def sweep_file(spec):
    return f"results/sweeps/{curve_id(spec)}.nc"


def needs_tmd(fig):
    return bool(config["figures"][fig].get("tmd", False))


def curve_params(wildcards):
    """Only what one curve's numbers depend on, so unrelated edits rerun nothing."""
    spec = CURVES[wildcards.curve]
    out = {"structure": config["structure"], "protocol": config["protocol"], "spec": spec}
    if spec.get("nu", 0.0):
        out["friction"] = friction_scale(config, spec)
    return out


def table_curves(wildcards):
    """The curves the paper's reported values refer to, where the study has them."""
    wanted = {curve_id(s) for s in comparison.needed_curves()}
    return [sweep_file(spec) for cid, spec in CURVES.items() if cid in wanted]


def executor_name(wildcards):
    """The executor this Snakemake was started with (local, slurm, ...), for the report."""
    plugin = workflow.executor_plugin
    return plugin.name if plugin is not None else "unknown"


def report_benchmarks():
    """The benchmark file of every job of the study, for the report's run times."""
    files = [f"results/benchmarks/sweep_curve/{c}.tsv" for c in CURVES]
    files += [f"results/benchmarks/figure/{fig}.tsv" for fig in FIGURES]
    files += ["results/benchmarks/tmd_optimum.tsv", "results/benchmarks/paper_vs_reproduced.tsv"]
    if MASRI_OUTPUTS:
        rules_ = ("masri_check", "masri_chart", "masri_branches", "masri_figures")
        files += [f"results/benchmarks/{r}.tsv" for r in rules_]
    for spec in COEXISTENCE_CURVES:
        c = curve_id(spec)
        files += [f"results/benchmarks/continuation_curve/{c}_{m}.tsv" for m in COEXISTENCE_MODES]
        rules_ = ("ensemble_curve", "coexistence_figure", "hysteresis_figure")
        files += [f"results/benchmarks/{r}/{c}.tsv" for r in rules_]
    if COEXISTENCE_CURVES:
        files.append("results/benchmarks/coexistence_table.tsv")
    if NUMERICS_OUTPUTS:
        files += [f"results/benchmarks/{r}.tsv" for r in ("numerics_work_precision", "numerics_stability",
                                                          "numerics_figures")]
    if VALIDATION:
        files.append("results/benchmarks/cross_validation.tsv")
    return files


def archive_extras():
    """Outputs of the stages that run only when configured (datasets, figures, tables), for the archive."""
    files = list(MASRI_OUTPUTS + COEXISTENCE_OUTPUTS)
    files += [f"{f[:-4]}.pdf" for f in files if f.startswith("results/figures/") and f.endswith(".png")]
    if MASRI_OUTPUTS:
        files += [f"results/checks/{name}.nc" for name in ("masri", "masri_chart", "masri_branches")]
    for spec in COEXISTENCE_CURVES:
        files += [f"results/coexistence/{curve_id(spec)}_{m}.nc" for m in [*COEXISTENCE_MODES, "ensemble"]]
    if COEXISTENCE_CURVES:
        files.append("results/tables/coexistence_e_trend.json")
    if NUMERICS_OUTPUTS:
        files += NUMERICS_OUTPUTS + ["results/numerics/work_precision.nc", "results/figures/numerics_stability_map.png"]
    if VALIDATION:
        files += [f"results/validation/{f}" for f in ("validation_table.csv", "validation_curves.csv",
                                                       "validation_delta.csv", "drop_tests.csv", "claims.json",
                                                       "fig3.png", "fig5.png")]
    return files
