"""The house in layers: imports go down, the model compiles nothing, and every rule's library is derived.

The layers (docs/architecture.md), lowest first: ``model`` (what is simulated), then ``engine`` (how),
``closed_form`` and ``baselines`` (answers without the engine), then ``outputs`` (files, figures, report),
then ``rig`` (the virtual test rig, which writes its runs in the measurement format), then ``stages``, then the
command line.  Each import statement of the package, those inside functions
included, is checked against the table below, so a shortcut upwards fails here the day it is written.
"""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from impact.outputs import code_deps

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
PACKAGE = SRC / "impact"
RULES = ROOT / "workflow" / "rules"
SCRIPTS = ROOT / "workflow" / "scripts"

# which top-level parts of the package each part may import (besides itself)
MAY_IMPORT = {
    "kernels": set(),
    "model": set(),
    "engine": {"model"},
    "closed_form": {"model"},
    "baselines": {"model"},
    "outputs": {"model", "kernels"},
    "rig": {"model", "engine", "outputs"},
    "stages": {"model", "engine", "closed_form", "baselines", "outputs", "rig"},
    "cli": {"model", "engine", "closed_form", "baselines", "outputs", "rig", "stages"},
    "__init__": set(),
    "__main__": {"kernels", "cli"},
}
# a script that two rules share, named after neither: the rules differ only in which figure's data they write
SHARED_SCRIPTS = {"validation_fig3_data": "validation_figure_data", "validation_fig5_data": "validation_figure_data"}


def _part(path: Path, package_dir: Path = PACKAGE) -> str:
    rel = path.relative_to(package_dir)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def _imports(path: Path, src: Path = SRC):
    """(line, imported module) of every import statement of a file, function-level ones included."""
    package = ".".join(path.relative_to(src).with_suffix("").parts[:-1])
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[: len(parts) - node.level + 1] + ([base] if base else []))
            yield node.lineno, base
            for alias in node.names:
                yield node.lineno, f"{base}.{alias.name}"


def _library_modules():
    return sorted(PACKAGE.rglob("*.py"))


def test_every_part_of_the_package_is_in_the_layer_table():
    assert {_part(p) for p in _library_modules()} <= set(MAY_IMPORT)


def _upward_imports(path: Path, src: Path = SRC) -> list:
    """The imports of a module of the package that go above its layer, as 'line N: module'."""
    own = _part(path, src / "impact")
    allowed = MAY_IMPORT[own] | {own}
    upward = []
    for line, name in _imports(path, src):
        if name.startswith("impact."):
            target = name.split(".")[1]
            if target in MAY_IMPORT and target not in allowed:
                upward.append(f"line {line}: {name}")
    return upward


@pytest.mark.parametrize("path", _library_modules(), ids=lambda p: str(p.relative_to(PACKAGE)))
def test_imports_go_down_the_layers(path):
    upward = _upward_imports(path)
    assert not upward, f"{path.relative_to(ROOT)} ({_part(path)}) imports above its layer: {upward}"


#: the engine's ways in for the parts above it: the entry point (run: simulate for scenes, simulate_system and
#: sweep for the paper's system on it) and Sa on a one-storey scene (spectra, itself a run.simulate)
ENGINE_ENTRIES = {"impact.engine.run", "impact.engine.spectra"}
#: what reaches the engine's insides, and why: the compile command compiles the loops; the rig takes the engine's
#: compile lock for its own kernels
ENGINE_INSIDE = {"cli/upkeep.py", "rig/simulator.py"}


def test_the_stages_and_the_command_line_come_into_the_engine_through_its_entry_point():
    """No stage, command or output runs a loop around the dispatch (engine.run.LOOPS): they import the engine's
    entry modules only, except the few named, each with its reason."""
    around = {}
    for path in _library_modules():
        rel = str(path.relative_to(PACKAGE))
        if _part(path) not in ("stages", "cli", "outputs", "rig") or rel in ENGINE_INSIDE:
            continue
        inside = {name for _, name in _imports(path) if name.startswith("impact.engine.")
                  and not any(name == e or name.startswith(e + ".") for e in ENGINE_ENTRIES)}
        # "from impact.engine.run import x" also yields "impact.engine.run.x"; a bare "from impact.engine import
        # run" yields "impact.engine.run"
        if inside:
            around[rel] = sorted(inside)
    assert not around, f"around the engine's entry point: {around}"


def test_the_layer_check_catches_every_form_of_an_upward_import(tmp_path):
    """On a synthetic package: absolute, from-, relative and function-level imports upwards are all found,
    and imports down the layers or of the module's own part are not."""
    engine = tmp_path / "impact" / "engine"
    engine.mkdir(parents=True)
    (engine / "loop.py").write_text(
        "import impact.stages.sweeps\n"
        "from impact.outputs import files\n"
        "from ..stages import numerics\n"
        "from impact.model.params import System\n"
        "from . import segment\n"
        "def late():\n"
        "    from impact.cli import main\n")
    found = _upward_imports(engine / "loop.py", tmp_path)
    assert found == ["line 1: impact.stages.sweeps", "line 2: impact.outputs", "line 2: impact.outputs.files",
                     "line 3: impact.stages", "line 3: impact.stages.numerics", "line 7: impact.cli",
                     "line 7: impact.cli.main"]


@pytest.mark.parametrize("path", sorted((PACKAGE / "model").rglob("*.py")), ids=lambda p: p.name)
def test_the_model_never_imports_numba(path):
    assert not [n for _, n in _imports(path) if n == "numba" or n.startswith("numba.")]


def test_importing_the_model_loads_no_numba_and_the_engine_no_stage_or_output():
    """At run time too: the whole model, then the whole engine, and what each has loaded."""
    code = """
import importlib, json, pkgutil, sys
import impact.model, impact.engine
def load(pkg):
    for info in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
        importlib.import_module(info.name)
load(impact.model)
after_model = sorted(sys.modules)
load(impact.engine)
print(json.dumps({"model": after_model, "engine": sorted(sys.modules)}))
"""
    out = json.loads(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)
    assert not [m for m in out["model"] if m == "numba" or m.startswith("numba.")]
    assert not [m for m in out["engine"] if m.startswith(("impact.stages", "impact.outputs", "impact.cli"))]


def _rules():
    """(rule, script, the rule's library argument) of every rule that runs a script."""
    found = []
    for smk in sorted(RULES.glob("*.smk")):
        for block in re.split(r"(?m)^(?=rule )", smk.read_text())[1:]:
            name = block.split()[1].rstrip(":")
            script = re.search(r'script:\s+"\.\./scripts/(\w+)\.py"', block)
            if script:
                library = re.findall(r'library=library\("(\w+)"\)', block)
                found.append((name, script.group(1), library))
    return found


def test_every_rule_runs_the_script_named_after_it_and_tracks_that_scripts_library():
    rules = _rules()
    assert len(rules) > 30
    for name, script, library in rules:
        assert script == SHARED_SCRIPTS.get(name, name), f"rule {name} runs scripts/{script}.py"
        assert library == [script], f"rule {name}: its library param must be library({script!r}), not {library}"
    # the hand-typed lists are gone
    assert "LIB_" not in (RULES / "common.smk").read_text()


#: the package's data files, as pyproject.toml declares them (read at run time beside their modules)
PACKAGE_DATA = {path for pattern in tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
    "package-data"]["impact"] for path in PACKAGE.glob(pattern)}


def test_a_scripts_library_is_its_transitive_impact_imports():
    """Against an independent reading: a breadth-first walk over this file's own import parser."""
    for script in sorted(SCRIPTS.glob("*.py")):
        expected, todo = set(), [script]
        while todo:
            path = todo.pop()
            reader = _imports if path.is_relative_to(SRC) else _script_imports
            for _, name in reader(path):
                parts = name.split(".")
                for i in range(1, len(parts) + 1):
                    found = code_deps.module_file(".".join(parts[:i]), SRC)
                    if found is not None and found not in expected:
                        expected.add(found)
                        todo.append(found)
        data = {p for p in PACKAGE_DATA if any(e.parent == p.parent for e in expected)}
        assert set(code_deps.library_files(script, SRC)) == expected | data, script.name


def _script_imports(path: Path):
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            yield node.lineno, node.module
            for alias in node.names:
                yield node.lineno, f"{node.module}.{alias.name}"


@pytest.mark.slow
def test_what_a_script_loads_at_run_time_is_within_its_library():
    """Executing a script's imports loads no impact module its library leaves out."""
    code = """
import ast, json, sys
path = sys.argv[1]
for node in ast.parse(open(path).read()).body:
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        exec(compile(ast.Module([node], []), path, "exec"))
print(json.dumps(sorted(m.__file__ for n, m in sys.modules.items() if n.startswith("impact") and m.__file__)))
"""
    for script in sorted(SCRIPTS.glob("*.py")):
        proc = subprocess.run([sys.executable, "-c", code, str(script)], capture_output=True, text=True, check=True)
        loaded = {Path(f).resolve() for f in json.loads(proc.stdout)}
        library = set(code_deps.library_files(script))
        assert loaded <= library, (script.name, sorted(map(str, loaded - library)))


#: the scripts of the jobs the study runs by the dozen (one per building and damper, each a few seconds of runs)
RUN_JOBS = ("ida_bare", "ida_damper", "loads_bare", "loads_damper", "collapse_bare", "collapse_damper")


def test_the_run_jobs_load_no_optimiser_or_distribution():
    """scipy.optimize and scipy.stats cost a job 0.1 to 0.4 s to import (docs/performance.md, "What a job loads"),
    and a job that designs a TMD (Den Hartog's closed form) or reads P695's normal tail (ndtr) needs neither."""
    code = """
import ast, json, sys
path = sys.argv[1]
for node in ast.parse(open(path).read()).body:
    if isinstance(node, (ast.Import, ast.ImportFrom)):
        exec(compile(ast.Module([node], []), path, "exec"))
print(json.dumps(sorted(n for n in sys.modules if n in ("scipy.optimize", "scipy.stats"))))
"""
    for name in RUN_JOBS:
        proc = subprocess.run([sys.executable, "-c", code, str(SCRIPTS / f"{name}.py")], capture_output=True,
                              text=True, check=True)
        assert json.loads(proc.stdout) == [], name


def test_a_content_edit_changes_the_digest_of_exactly_the_scripts_that_reach_it(tmp_path):
    import shutil

    copy = tmp_path / "src"
    shutil.copytree(SRC / "impact", copy / "impact", ignore=shutil.ignore_patterns("__pycache__"))
    before = {s.stem: code_deps.library_digest(s, copy) for s in SCRIPTS.glob("*.py")}
    edited = copy / "impact" / "engine" / "contact.py"
    edited.write_text(edited.read_text() + "\nAN_EDIT = 1\n")
    after = {s.stem: code_deps.library_digest(s, copy) for s in SCRIPTS.glob("*.py")}
    reaches = {s.stem for s in SCRIPTS.glob("*.py") if edited.resolve() in code_deps.library_files(s, copy)}
    assert {s for s in before if before[s] != after[s]} == reaches
    assert {"sweep_curve", "design_sweep", "continuation_curve", "ensemble_curve", "masri_check",
            "validation_cases", "numerics_work_precision_piece", "loads_damper", "robustness_design"} <= reaches
    assert not {"figure", "report", "tmd_optimum", "paper_vs_reproduced"} & reaches


def test_an_edit_of_comments_and_layout_alone_reruns_no_job(tmp_path):
    """A comment or a blank line cannot change a result, so it changes no script's digest; a docstring can be
    printed, so it does."""
    import shutil

    copy = tmp_path / "src"
    shutil.copytree(SRC / "impact", copy / "impact", ignore=shutil.ignore_patterns("__pycache__"))
    script = SCRIPTS / "sweep_curve.py"
    edited = copy / "impact" / "engine" / "contact.py"
    before = code_deps.library_digest(script, copy)
    source = edited.read_text()
    edited.write_text("# a comment\n\n" + source.replace("\n\n\n", "\n\n\n\n") + "\n# an edit\n")
    assert code_deps.library_digest(script, copy) == before
    edited.write_text(source.replace('"""', '"""A docstring edit. ', 1))
    assert code_deps.library_digest(script, copy) != before


def test_the_rules_take_the_damper_kinds_from_the_model():
    """No rules file spells the damper kinds out: their wildcard patterns come from DAMPER_KINDS and
    IMPACT_KINDS (common.smk), so a new kind in the model matches every rule."""
    from impact.model.params import IMPACT_KINDS
    from impact.model.scene import DAMPER_KINDS

    spelt = re.compile("|".join(rf"\b{kind}\|" for kind in {*DAMPER_KINDS, *IMPACT_KINDS}))
    found = [f"{smk.name}:{i}" for smk in sorted(RULES.glob("*.smk"))
             for i, line in enumerate(smk.read_text().splitlines(), 1) if spelt.search(line)]
    assert found == []
