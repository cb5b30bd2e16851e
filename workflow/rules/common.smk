# Shared helpers: the study's curves from the configuration, library sources
# as rule inputs (Snakemake does not track what a script imports).
import os

from impact import comparison
from impact.study import all_curves, check_config, curve_id, figure_curves, friction_scale

check_config(config)

FIGURES = list(config["figures"])
CURVES = all_curves(config)

ENV = "../envs/impact.yaml"


def library(*names):
    """Library source files a rule's script imports, as its inputs."""
    return [os.path.join("src", "impact", name) for name in names]


LIB_CORE = library("__init__.py", "params.py", "_kernels.py", "simulate.py", "provenance.py", "pipeline.py")
LIB_SWEEP = LIB_CORE + library("dataset.py", "study.py")
LIB_TMD = library("tmd.py", "pipeline.py", "params.py")
LIB_PLOT = library("plotting.py", "study.py", "pipeline.py")
LIB_TABLE = library("comparison.py", "study.py", "pipeline.py")


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
