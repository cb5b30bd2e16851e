# Shared helpers: the configuration's validation, the study's curves from it, input and param functions.
import dataclasses
import os
import re

import yaml
from jsonschema import ValidationError
from snakemake.exceptions import WorkflowError
from snakemake.utils import validate

from impact.stages import tables as comparison
from impact.outputs.archive import archive_name
from impact.outputs.code_deps import library_digest
from impact.outputs.labels import label
from impact.rig.config import SCHEMA_PATH as RIG_SCHEMA
from impact.rig.config import validation_config
from impact.stages.validation.grid import batches as rig_batches
from impact.stages.validation.grid import study_cases
from impact.stages.numerics.plan import stability_families, work_precision_pieces
from impact.outputs.provenance import git_state
from impact.stages.loads import plan as loads
from impact.stages.buildings import buildings as stage_buildings
from impact.stages.buildings import shared_keys, wildcard
from impact.stages.ida import plan as ida
from impact.stages.collapse import plan as collapse
from impact.model.params import IMPACT_KINDS
from impact.model.kinds import CID, kind_of
from impact.model.scene import DAMPER_KINDS
from impact.stages.design import chart_specs
from impact.stages.robustness.designs import design_curves, design_names
from impact.stages.sweeps import all_curves, check_config, figure_curves, friction_scale
from impact.model.params import curve_id


def validate_naming_the_key(config, schema, what="config"):
    """The schema's check of ``config`` (``what`` names it), with its error as one line naming the key and what is wrong (Snakemake's own
    message prints the whole schema after it: two thousand lines for a misspelt key)."""
    try:
        validate(config, schema)
    except WorkflowError as exc:
        error = exc.__context__  # the schema's error, which Snakemake raised its own while handling
        if not isinstance(error, ValidationError):
            raise
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in error.absolute_path)
        about = error.schema.get("description") if isinstance(error.schema, dict) else None
        raise WorkflowError(
            f"{what} {where.lstrip('.') or '(top level)'}: {error.message}"
            + (f"\n  the key: {about}" if about and error.absolute_path else "")
            + (YAML_NUMBER_HINT if _a_number_read_as_text(error) else "")
        ) from None


#: YAML 1.1 (PyYAML) reads 2.0e5 as text: its exponent needs a sign
YAML_NUMBER_HINT = "\n  YAML reads a number like 2.0e5 as text: write 2.0e+5 (the exponent signed) or 200000.0"


def _a_number_read_as_text(error) -> bool:
    if error.validator != "type" or not isinstance(error.instance, str):
        return False
    try:
        float(error.instance)
    except ValueError:
        return False
    return True


validate_naming_the_key(config, os.path.join(workflow.current_basedir, "..", "schemas", "config.schema.yaml"))
check_config(config)

# the wildcard patterns of the damper kinds, from the model's registries: a new kind matches every rule
ANY_KIND = "|".join(DAMPER_KINDS)
WALLED_KIND = "|".join(IMPACT_KINDS)
# the curves of the CID, whose coexisting steady states the coexistence stage traces
CID_CURVE = f"{CID}_[A-Za-z0-9_.]+"

FIGURES = list(config["figures"])
CURVES = all_curves(config)

ENV = "../envs/impact.yaml"
# the workflow's description (OVERVIEW, in the Snakefile), beside every caption and the page template
REPORT_DIR = os.path.dirname(OVERVIEW)

# The report's sections, in order: the category of every report() flag, so that
# Snakemake's report (which sorts them by name: hence 01 to 10) and the HTML page agree.
SECTIONS = {
    "paper": "01. The paper's values beside ours",
    "figures": "02. The paper's figures",
    "validation": "03. Experiment (cross-validation)",
    "masri": "04. Closed form (Masri, 2 EIPC)",
    "coexistence": "05. Initial conditions and coexisting states",
    "numerics": "06. Numerics",
    "robustness": "07. Table 1 in numbers",
    "design": "08. Design charts",
    "loads": "09. Earthquakes and wind on real buildings",
    "ida": "10. Incremental dynamic analysis on the FEMA P695 suites",
    "collapse": "11. Collapse of yielding buildings (FEMA P695)",
}


def figure_title(fig):
    """A configured figure's title in the reports: its number and its title in the configuration."""
    number, title = fig.removeprefix("fig").lstrip("0"), config["figures"][fig].get("title")
    return f"Fig. {number}: {title}" if title else f"Fig. {number}"


# the workflow's scripts, each named after its rule, and the library beside the workflow they import
SCRIPTS = os.path.join(workflow.current_basedir, "..", "scripts")
LIBRARY_SRC = os.path.join(workflow.current_basedir, "..", "..", "src")


def library(script):
    """The library code a rule's script runs: a digest of its transitive impact imports (code_deps), as a param.

    Snakemake tracks the script itself, not what it imports; as a param the digest reruns exactly the jobs whose
    scripts reach an edited file, and the scheduler has no library files to stat.
    """
    return library_digest(os.path.join(SCRIPTS, f"{script}.py"), LIBRARY_SRC)


# stages that run only when configured (and, for those beyond the paper, not skipped: config/paper.yaml)
SKIPPED_STAGES = set(config.get("skip_stages", []))
# a run that skips stages (make paper) writes a report and an archive of its own, so that it never replaces the
# whole study's with a page that lacks the skipped stages' sections
SCOPE = "paper" if SKIPPED_STAGES else "study"
REPORT = "results/report/index.html" if SCOPE == "study" else f"results/report/{SCOPE}.html"
# one archive per commit and scope, "-dirty" when the source tree has uncommitted changes
ARCHIVE = f"results/archive/{archive_name(git_state()['git_commit'], git_state()['git_dirty'], scope=SCOPE)}"


def stage_config(name):
    """A configured stage's section, or None when it is not configured or skip_stages names it."""
    return None if name in SKIPPED_STAGES else config.get(name)


MASRI = "masri" in config
NUMERICS = "numerics" in config
VALIDATION = config.get("validation", {})
# the numerics' pieces of work: (case, method family) of the work-precision runs, families of the extreme cases
NUMERICS_PIECES = work_precision_pieces(config["numerics"]) if NUMERICS else []
STABILITY_FAMILIES = stability_families(config["numerics"]) if NUMERICS else []

# the synthetic experiment: the rig's file, validated against its schema (which fills in every
# default), and the cases of its grid (the smoke subset when asked)
RIG_FILE = VALIDATION.get("config", "config/validation.yaml")
RIG, RIG_CASES, RIG_WALLS, RIG_SETUPS = {}, {}, [], []
if VALIDATION:
    with open(RIG_FILE) as fh:
        RIG = yaml.safe_load(fh) or {}
    validate_naming_the_key(RIG, str(RIG_SCHEMA), what=RIG_FILE)
    RIG = validation_config(RIG, smoke=VALIDATION.get("smoke", False))
    _cases = study_cases(RIG, VALIDATION.get("smoke", False))
    RIG_CASES = {c.id: dataclasses.asdict(c) for c in _cases}
    # one job per wall, each running every setup (ball, gap, r') on it
    RIG_WALLS, RIG_SETUPS = rig_batches(_cases)
# Table 1 in numbers: its designs, and the sweeps their optimum gaps come from
ROBUSTNESS = stage_config("robustness") is not None
ROBUSTNESS_DESIGNS = design_names(config) if ROBUSTNESS else []
# design charts: the sweeps they read, per damper
DESIGN = stage_config("design")
DESIGN_KINDS = list(DAMPER_KINDS) if DESIGN else []
DESIGN_CURVES = {kind: {curve_id(s): s for s in chart_specs(DESIGN, kind)} for kind in IMPACT_KINDS} if DESIGN else {}
# the earthquake and wind study: its buildings, dampers and load families
LOADS = stage_config("loads")
if LOADS:
    loads.check_config(LOADS)
LOADS_BUILDINGS = list(stage_buildings(LOADS)) if LOADS else []
BUILDING_IDS = wildcard(LOADS_BUILDINGS)  # the {building} wildcard of the loads, ida and collapse rules
LOADS_FAMILIES = loads.families(LOADS) if LOADS else []
LOADS_KINDS = list(DAMPER_KINDS)
# incremental dynamic analysis: on the loads stage's buildings, with its damper designs
IDA = stage_config("ida")
if IDA:
    ida.check_config(IDA, LOADS)
IDA_BUILDINGS = ida.stage_buildings(LOADS) if IDA else []
IDA_KINDS = list(DAMPER_KINDS)
# collapse: the ida stage's buildings made to yield, with its ground motions and damper designs
COLLAPSE = stage_config("collapse")
if COLLAPSE:
    collapse.check_config(COLLAPSE, IDA, LOADS)
COLLAPSE_BUILDINGS = IDA_BUILDINGS if COLLAPSE else []
COEXISTENCE_CURVES = config.get("coexistence", {}).get("curves", [])
COEXISTENCE_MODES = config.get("coexistence", {}).get("modes", ["continuation_up", "continuation_down"])


def sweep_file(spec):
    """The sweep dataset of one curve (the sweep_curve rule's output)."""
    return expand(rules.sweep_curve.output[0], curve=curve_id(spec))[0]


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


def robustness_curves():
    """The sweeps whose optimum gaps are the robustness stage's CID and PID design points."""
    specs = design_curves(config)
    missing = [curve_id(s) for s in specs if curve_id(s) not in CURVES]
    if missing:
        raise WorkflowError(
            f"robustness: its designs need the sweeps {', '.join(missing)}; add them to a figure's curves"
        )
    return specs


def robustness_sweeps(wildcards):
    return [sweep_file(spec) for spec in robustness_curves()]


def robustness_params(wildcards):
    """Only what the stage's numbers depend on."""
    return {key: config[key] for key in ("robustness", "structure", "protocol")}


def design_chart_params():
    """What a chart's numbers depend on: not the design equations fitted on it."""
    design = {key: value for key, value in DESIGN.items() if key != "equations"}
    return {"structure": config["structure"], "protocol": config["protocol"], "design": design}


def design_curve_params(wildcards):
    """Only what one chart sweep's numbers depend on."""
    spec = next(c[wildcards.curve] for c in DESIGN_CURVES.values() if wildcards.curve in c)
    return {
        "structure": config["structure"],
        "protocol": config["protocol"],
        "design": {"freq": DESIGN["freq"]},
        "spec": spec,
    }


def loads_params(wildcards):
    """What the stage's runs depend on: the loads section but the one case drawn in time."""
    return {key: value for key, value in LOADS.items() if key != "time_history"}


def ida_params(wildcards):
    """What the stage's damper runs depend on: its section but the verdicts' and fits' settings, and the loads keys
    it uses."""
    kept = {key: value for key, value in IDA.items() if key not in ("verdict", "drift_limits")}
    return {"ida": kept, "loads": shared_keys(LOADS)}


def ida_bare_params(wildcards):
    """What the bare runs depend on: the damper runs' keys but the dampers' designs'."""
    return bare_of(ida_params(wildcards))


def collapse_params(wildcards):
    """What the stage's damper runs depend on: its section but the tables' settings, and the ida and loads keys it
    uses."""
    kept = {key: value for key, value in COLLAPSE.items() if key not in ("ratings", "verdict")}
    return {
        "collapse": kept,
        "ida": {key: IDA[key] for key in collapse.IDA_KEYS},
        "loads": shared_keys(LOADS),
    }


def collapse_bare_params(wildcards):
    """What the bare archetype's runs depend on: the damper runs' keys but the dampers' designs'."""
    return bare_of(collapse_params(wildcards))


def bare_of(params):
    """A damper rule's params without the ida keys only a damper's design reads (ida.DESIGN_KEYS)."""
    return params | {"ida": {k: v for k, v in params["ida"].items() if k not in ida.DESIGN_KEYS}}


def ida_design(wildcards):
    """The earthquake study's damper run whose design gap ratio an impact damper takes (none for the TMD)."""
    if not kind_of(wildcards.damper).walls:
        return []
    return expand(rules.loads_damper.output[0], building=wildcards.building, damper=wildcards.damper)


def design_chart_sweeps(wildcards):
    """The sweeps one damper's chart reads (none for the TMD's, which is closed form)."""
    return expand(rules.design_sweep.output[0], curve=list(DESIGN_CURVES.get(wildcards.kind, {})))
