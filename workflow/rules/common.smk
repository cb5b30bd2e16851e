# Shared helpers: the study's curves from the configuration, library sources
# as rule inputs (Snakemake does not track what a script imports).
from impact.study import all_curves, check_config, curve_id, figure_curves
from impact import comparison

check_config(config)

FIGURES = list(config["figures"])
CURVES = all_curves(config)

LIB = "src/impact/"
LIB_CORE = [LIB + f for f in ("__init__.py", "params.py", "_kernels.py", "simulate.py", "provenance.py")]
LIB_SWEEP = LIB_CORE + [LIB + f for f in ("dataset.py", "study.py", "pipeline.py")]
LIB_TMD = [LIB + "tmd.py", LIB + "pipeline.py"]
LIB_PLOT = [LIB + "plotting.py", LIB + "study.py", LIB + "pipeline.py"]
LIB_TABLE = [LIB + "comparison.py", LIB + "study.py", LIB + "pipeline.py"]


def sweep_file(spec):
    return f"results/sweeps/{curve_id(spec)}.nc"


def needs_tmd(fig):
    return bool(config["figures"][fig].get("tmd", False))


def curve_params(wildcards):
    """Only what one curve's numbers depend on, so unrelated edits rerun nothing."""
    spec = CURVES[wildcards.curve]
    out = {"structure": config["structure"], "protocol": config["protocol"], "spec": spec}
    if spec.get("nu", 0.0):
        out["friction"] = config["friction"]
    return out
