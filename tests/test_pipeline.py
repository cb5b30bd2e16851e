"""The Snakemake pipeline: smoke DAG end to end, targeted rebuilds, config validation."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr
from reference import HANG_GUARD_S, copy_workflow

from impact.model.scene import DAMPER_KINDS

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
pytestmark = [pytest.mark.slow, pytest.mark.long_file(minutes=11)]  # started first, the longest first (conftest)


def _copy_workflow(dest: Path) -> Path:
    return copy_workflow(ROOT, dest)


def _snakemake(cwd: Path, *args: str, check=True) -> subprocess.CompletedProcess:
    proc = subprocess.run([*SNAKEMAKE, *args], cwd=cwd, capture_output=True, text=True, timeout=HANG_GUARD_S)
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    return proc


@pytest.fixture(scope="module")
def smoke(tmp_path_factory) -> Path:
    work = _copy_workflow(tmp_path_factory.mktemp("smoke"))
    _snakemake(work, "--cores", "2", "--configfile", "config/smoke.yaml")
    return work


def test_smoke_dag_produces_every_output(smoke):
    for fig in ("fig08", "fig09", "fig11"):
        for ext in ("png", "pdf"):
            path = smoke / "results" / "figures" / f"{fig}.{ext}"
            assert path.stat().st_size > 5000, path
    table = (smoke / "results" / "tables" / "paper_vs_reproduced.csv").read_text()
    assert "X_m at optimum g" in table and "optimum beta_t" in table
    optima = pd.read_csv(smoke / "results" / "tables" / "paper_vs_reproduced.csv").query("quantity == 'X_m at optimum g'")
    assert (optima["refined_at_g_optimum"] >= optima["reproduced"]).all()
    assert (optima["grid_underestimate"] >= 0).all()
    table1 = pd.read_csv(smoke / "results" / "tables" / "table1_measured.csv").set_index(["row", "design"])
    assert set(table1.index.get_level_values("row")) == {2, 5, 6, 7, 9, 10}
    assert table1.loc[(9, "tmd"), "number"] <= 1e-9  # a TMD is linear
    # every job left a log and a benchmark beside its output
    assert list((smoke / "results" / "logs" / "sweep_curve").glob("*.log"))
    assert list((smoke / "results" / "benchmarks" / "sweep_curve").glob("*.tsv"))
    # no temporary file survives a finished run
    assert not list((smoke / "results").rglob("*.tmp"))


def test_sweep_dataset_is_self_describing_and_round_trips(smoke, tmp_path):
    path = smoke / "results" / "sweeps" / "cid_mu0.01_e0.25.nc"
    with xr.open_dataset(path) as ds:
        ds.load()
    assert set(ds["start"].values) == {"centre", "left"}
    for name in list(ds.data_vars) + list(ds.coords):
        if name == "start":
            continue
        assert "long_name" in ds[name].attrs, name
        assert "units" in ds[name].attrs or "flag_meanings" in ds[name].attrs, name
    for key in ("title", "source", "git_commit", "git_dirty", "config", "curve", "date_created",
                "initial_condition", "param_mu", "param_e"):
        assert key in ds.attrs, key
    # a CID dataset holds no pendulum or friction fields
    assert "param_rp" not in ds.attrs and "param_nu" not in ds.attrs
    assert json.loads(ds.attrs["curve"])["damper"] == "cid"
    # the reductions are those of the per-frequency data
    np.testing.assert_array_equal(ds["x_max"].values, ds["amplitude"].max("freq_ratio").values)
    # round trip: write with the library's writer, read back, identical data and attributes
    from impact.outputs.files import write_dataset

    again = tmp_path / "again.nc"
    write_dataset(ds, again)
    with xr.open_dataset(again) as back:
        back.load()
    # the writer adds one line to the history (CF: each program that writes the file says so), nothing else
    assert back.attrs.pop("history").split("\n")[:-1] == ds.attrs.pop("history").split("\n")
    xr.testing.assert_identical(back, ds)
    with xr.open_dataset(smoke / "results" / "sweeps" / "pid_mu0.01_e0.25_rp1.nc") as pid:
        assert pid.attrs["param_rp"] == 1.0


def test_smoke_numbers_match_the_frozen_study(smoke):
    """The smoke study's numbers (run times aside) are the frozen ones, each within its own round-off
    sensitivity measured over BLAS kernel sets: see smoke_digest and within_round_off."""
    from reference import smoke_digest, within_round_off

    frozen = json.loads((ROOT / "tests" / "data" / "smoke_reference.json").read_text())["entries"]
    now = smoke_digest(smoke / "results")
    assert sorted(now) == sorted(frozen)
    missed = {key: miss for key, entry in frozen.items() if (miss := within_round_off(entry, now[key]))}
    assert not missed, missed


def test_the_fingerprint_tolerance_is_each_entrys_own():
    """An entry that round-off moves gets the room its spread measures; one it does not move keeps 1e-9, and
    its counts exactly."""
    from reference import within_round_off

    steady = {"stats": [10, 100.0, 1000.0, 0], "spread": [0, 0.0, 0.0, 0]}
    assert within_round_off(steady, [10, 100.0 + 5e-8, 1000.0, 0]) == []
    assert within_round_off(steady, [10, 100.0 + 2e-7, 1000.0, 0]) != []
    assert within_round_off(steady, [11, 100.0, 1000.0, 0]) != []
    assert within_round_off(steady, [10, 100.0, 1000.0, 1]) != []
    sensitive = {"stats": [10, 100.0, 1000.0, 0], "spread": [1, 1e-6, 0.0, 1]}
    assert within_round_off(sensitive, [10, 100.0 + 2.9e-6, 1000.0, 0]) == []
    assert within_round_off(sensitive, [10, 100.0 + 3.1e-6, 1000.0, 0]) != []
    assert within_round_off(sensitive, [9, 100.0, 1000.0, 1]) == []


def test_every_dataset_of_the_study_is_self_describing(smoke):
    """Every .nc the smoke study writes carries CF conventions, its provenance and a described variable each."""
    from impact.outputs.files import undescribed_variables

    paths = sorted((smoke / "results").rglob("*.nc"))
    assert len(paths) >= 10, paths  # sweeps, closed-form checks, coexistence, numerics
    for path in paths:
        with xr.open_dataset(path) as ds:
            assert ds.attrs.get("Conventions", "").startswith("CF-1."), path
            for key in ("source", "code_version", "git_commit", "date_created"):
                assert key in ds.attrs, (path, key)
            assert undescribed_variables(ds) == [], path


#: variables that count or flag, by the end of their name: stored as integers
WHOLE_SUFFIXES = ("impacts", "event_cap_reached", "two_ipc_at_max", "ipc_class", "ipc_class_at_max",
                  "sticking_episodes", "grazing_events", "failed", "nfev", "exists", "admissible", "stable", "stays")
#: global attributes a per-job piece carries about its one building, damper or record
PIECE_ATTRS = {"building": "building", "damper": "damper", "record": "record", "storeys": "building"}


def test_every_dataset_says_what_it_holds_in_the_checked_conventions(smoke):
    """Each dataset of the smoke study declares the CF version the checker checks, has a history and the configuration
    its job ran with, no global attribute naming one of the values its dimensions hold, units UDUNITS reads as meant
    (no "g", which is grams), flag attributes only on integer flags, and its counts and flags as integers."""
    from impact.outputs.files import CONVENTIONS

    assert CONVENTIONS == "CF-1.8"  # the version test_the_cf_checker_... checks against
    for path in sorted((smoke / "results").rglob("*.nc")):
        with xr.open_dataset(path, decode_cf=False) as ds:
            where = str(path.relative_to(smoke))
            assert ds.attrs["Conventions"] == CONVENTIONS and "written by impact-dampers" in ds.attrs["history"], where
            assert isinstance(json.loads(ds.attrs["config"]), dict), where
            for attr, dim in PIECE_ATTRS.items():
                assert not (attr in ds.attrs and dim in ds.dims), (where, attr)
            for name, var in {**ds.coords, **ds.data_vars}.items():
                assert var.attrs.get("units") != "g", (where, name)
                if "flag_values" in var.attrs:
                    assert var.dtype.kind in "iu" and "units" not in var.attrs, (where, name)
                    values = set(np.unique(var.values)) - {var.attrs.get("_FillValue")}
                    assert values <= set(var.attrs["flag_values"].tolist()), (where, name, values)
                if str(name).endswith(WHOLE_SUFFIXES):
                    assert var.dtype.kind in "iub", (where, name, var.dtype)


def test_the_cf_checker_finds_no_high_priority_fault_in_any_dataset(smoke, tmp_path):
    """The IOOS compliance-checker, CF 1.8, on every dataset of the smoke study."""
    from compliance_checker.runner import CheckSuite, ComplianceChecker

    CheckSuite.load_all_available_checkers()
    faults = {}
    for i, path in enumerate(sorted((smoke / "results").rglob("*.nc"))):
        out = tmp_path / f"{i}.json"
        ComplianceChecker.run_checker(str(path), ["cf:1.8"], 0, "normal", output_filename=str(out),
                                      output_format="json")
        checks = json.loads(out.read_text())["cf:1.8"]["high_priorities"]
        failed = [(c["name"], c["msgs"]) for c in checks if c["value"][0] < c["value"][1]]
        if failed:
            faults[str(path.relative_to(smoke))] = failed
    assert faults == {}


def test_a_registered_figure_reaches_the_report_and_the_archive(smoke, tmp_path):
    """One rule (registered) and one caption file, and nothing else, put a new figure in the report and archive."""
    import shutil
    import tarfile

    work = tmp_path / "copy"
    shutil.copytree(smoke, work, symlinks=True)
    (work / "workflow" / "report" / "dummy_figure.rst").write_text("**A dummy figure.** A line, to prove the point.\n")
    with open(work / "workflow" / "rules" / "figures.smk", "a") as smk:
        smk.write('''

rule dummy_figure:
    output:
        png=report(
            "results/figures/dummy_figure.png",
            caption="../report/dummy_figure.rst",
            category=SECTIONS["figures"],
            subcategory="A dummy figure",
        ),
    log:
        "results/logs/dummy_figure.log",
    benchmark:
        "results/benchmarks/dummy_figure.tsv"
    run:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots()
        ax.plot([0, 1], [0, 1])
        fig.savefig(output.png)


register(rules.dummy_figure, report=("png",))
''')
    _snakemake(work, "all", "archive", "--cores", "2", "--configfile", "config/smoke.yaml")
    page = (work / "results" / "report" / "index.html").read_text()
    assert '<section id="dummy_figure"><h3>A dummy figure</h3>' in page
    assert "<strong>A dummy figure.</strong> A line, to prove the point." in page
    (archive,) = (work / "results" / "archive").glob("*.tar.gz")
    with tarfile.open(archive) as tar:
        assert any(name.endswith("results/figures/dummy_figure.png") for name in tar.getnames())


def test_one_figure_dry_run_lists_only_its_jobs(smoke):
    # the target goes first: --configfile takes every word after it
    out = _snakemake(smoke, "results/figures/fig09.png", "-n", "--forceall",
                     "--configfile", "config/smoke.yaml").stdout
    jobs = _job_stats(out)
    # Fig. 9 of the smoke study: two CID curves, no TMD, no table
    assert jobs == {"sweep_curve": 2, "figure": 1, "total": 3}, out[-2000:]
    assert "pid_" not in out and "tmd_optimum" not in out


def _job_stats(out: str) -> dict[str, int]:
    start = out.rindex("Job stats:")
    table = out[start:out.index("Reasons:", start)]
    return {line.split()[0]: int(line.split()[1]) for line in table.splitlines()
            if len(line.split()) == 2 and line.split()[1].isdigit()}


def test_a_building_of_ones_own_runs_through_every_stage_on_real_loads(tmp_path):
    """loads.buildings: a non-uniform building named in the configuration gets the uniform ones' jobs in the
    loads, ida and collapse stages, under its name, and its IDA figure can be asked for alone."""
    own = tmp_path / "own.yaml"
    own.write_text("loads:\n  buildings:\n    frame-a: {masses_kg: [2.0e+5, 1.5e+5], "
                   "storey_stiffness_n_per_m: [6.0e+7, 3.0e+7]}\n")
    out = _snakemake(ROOT, "results/figures/ida_frame-a.png", "results/figures/collapse_frame-a.png", "-n",
                     "--forceall", "--configfile", "config/smoke.yaml", str(own)).stdout
    for rule in ("loads_bare", "ida_bare", "collapse_bare"):
        assert f"results/{rule.split('_')[0]}/runs/frame-a/bare.nc" in out, rule
    for kind in DAMPER_KINDS:
        assert f"results/ida/runs/frame-a/{kind}.nc" in out and f"results/collapse/runs/frame-a/{kind}.nc" in out


def test_the_papers_scope_skips_exactly_the_stages_beyond_it():
    """config/paper.yaml over the full configuration (make paper): every job of the paper's stages, none
    of Table 1 in numbers, the design charts, the loads, the incremental dynamic analysis or the collapse stage."""
    beyond = {"robustness", "design", "loads", "ida", "collapse"}
    full = _job_stats(_snakemake(ROOT, "-n", "--forceall").stdout)
    paper = _job_stats(_snakemake(ROOT, "-n", "--forceall", "--configfile", "config/config.yaml",
                                  "config/paper.yaml").stdout)
    stage_of = {}
    for smk in (ROOT / "workflow" / "rules").glob("*.smk"):
        for line in smk.read_text().splitlines():
            if line.startswith("rule "):
                stage_of[line.split()[1].rstrip(":")] = smk.stem
    assert {stage_of[r] for r in full if r in stage_of} >= beyond  # the full study has them
    assert not {stage_of[r] for r in paper if r in stage_of} & beyond
    kept = {r: n for r, n in full.items() if stage_of.get(r) not in beyond and r not in ("total", "report", "study",
                                                                                           "all", "archive")}
    assert {r: paper.get(r) for r in kept} == kept  # the paper's own jobs, all of them
    # a stage that cannot be skipped is refused by name
    proc = _snakemake(ROOT, "-n", "--configfile", "config/config.yaml", str(ROOT / "tests" / "data" / "skip_numerics.yaml"),
                      check=False)
    assert proc.returncode != 0 and "skip_stages" in proc.stdout + proc.stderr


def test_up_to_date_study_reruns_nothing(smoke):
    out = _snakemake(smoke, "-n", "--configfile", "config/smoke.yaml").stdout
    assert "Nothing to be done" in out or "nothing to be done" in out.lower()


def test_an_engine_edit_reruns_exactly_the_jobs_whose_scripts_reach_it(smoke):
    """A one-line content edit of the engine's contact module: every job whose script reaches the file through
    its imports is outdated, every simulating stage among them; a job is outdated for its params (its library
    digest) only if its script reaches the file; the closed-form jobs are not outdated.  Touching a file
    without changing it, or adding a comment, reruns nothing."""
    from impact.outputs import code_deps

    contact = smoke / "src" / "impact" / "engine" / "contact.py"
    original = contact.read_text()
    try:
        contact.touch()
        assert "nothing to be done" in _snakemake(smoke, "-n", "--configfile", "config/smoke.yaml").stdout.lower()
        contact.write_text(original + "\n# a comment alone\n")
        assert "nothing to be done" in _snakemake(smoke, "-n", "--configfile", "config/smoke.yaml").stdout.lower()
        contact.write_text(original + "\nA_ONE_LINE_EDIT = 1\n")
        out = _snakemake(smoke, "-n", "--configfile", "config/smoke.yaml").stdout
    finally:
        contact.write_text(original)
    changed = _rules_whose_params_changed(out)
    scripts = {}
    for smk in (smoke / "workflow" / "rules").glob("*.smk"):
        for block in smk.read_text().split("\nrule ")[1:]:
            script = re.search(r'script:\s+"\.\./scripts/(\w+)\.py"', block)
            if script:
                scripts[block.split(":")[0].strip()] = smoke / "workflow" / "scripts" / f"{script.group(1)}.py"
    reaching = {rule for rule, script in scripts.items()
                if contact.resolve() in code_deps.library_files(script, smoke / "src")}
    planned = set(_job_stats(out))
    everything = set(_job_stats(_snakemake(smoke, "-n", "--forceall", "--configfile", "config/smoke.yaml").stdout))
    # never fewer: every job whose script reaches the file is outdated
    assert reaching & everything <= planned, sorted((reaching & everything) - planned)
    # no more: a job is outdated for its code only if its script reaches the file (a job downstream of an
    # outdated one is outdated for its inputs; Snakemake then names that reason alone)
    assert changed and changed <= reaching, sorted(changed - reaching)
    assert {"sweep_curve", "design_sweep", "continuation_curve", "ensemble_curve", "masri_check",
            "validation_cases", "numerics_work_precision_piece", "loads_damper", "robustness_design", "ida_damper",
            "collapse_damper"} <= planned
    assert not {"tmd_optimum", "masri_chart"} & planned


def test_a_change_of_the_dampers_stroke_limit_reruns_their_runs_and_not_the_bare_ones(smoke, tmp_path):
    """ida.stroke_limit_m is read by the dampers' designs alone (ida.plan.DESIGN_KEYS): the damper runs of the ida
    and collapse stages are outdated for their params, the bare runs are not."""
    override = tmp_path / "stroke.yaml"
    override.write_text("ida:\n  stroke_limit_m: 0.05\n")
    out = _snakemake(smoke, "-n", "--configfile", "config/smoke.yaml", str(override)).stdout
    assert _rules_whose_params_changed(out) == {"ida_damper", "collapse_damper"}
    assert not {"ida_bare", "collapse_bare"} & set(_job_stats(out))


def _rules_whose_params_changed(out: str) -> set[str]:
    """The rules of a dry run's jobs whose reason is a change of params."""
    rules = set()
    for block in re.split(r"\n(?=(?:local)?rule \w+:)", out):
        head = re.match(r"(?:local)?rule (\w+):", block)
        reason = re.search(r"reason: ([^\n]*)", block)
        if head and reason and "params have changed" in reason.group(1).lower():
            rules.add(head.group(1))
    return rules


@pytest.mark.parametrize("patch,key", [
    # the key's whole path, where the schema's own message named only its last part
    ({"figures": {"fig09": {"panels": [{"curves": [{"damper": "cid", "mu": 0.01, "e": 1.5}]}]}}},
     "figures.fig09.panels[0].curves[0].e: 1.5 is greater than the maximum of 1"),
    ({"protocol": {"gap": {"min": -1.0, "max": 1.0, "step": 0.5}}}, "protocol.gap.min: -1.0 is less than"),
    ({"figures": {"fig09": {"panels": [{"curves": [{"damper": "tmd", "mu": 0.01, "e": 0.5}]}]}}},
     "figures.fig09.panels[0].curves[0].damper: 'tmd' is not one of"),
    ({"protocol": {"periods": 10, "average_from": 20}}, "protocol.average_from"),
    # a new user's two: Table 1's numbers of units without 1, and a NaN that bounds let through
    ({"robustness": {"units": [2, 4]}}, "robustness.units: [2, 4] does not contain"),
    ({"structure": {"beta": float("nan")}}, "structure.beta = nan"),
    # a PID the scenes would refuse (model.params.MAX_TUNING) is refused at parse time, by the config's name
    ({"figures": {"fig09": {"panels": [{"curves": [{"damper": "pid", "mu": 0.01, "e": 0.5, "rp": 500}]}]}}},
     "figures.fig09.panels[0].curves[0].rp: 500 is greater than the maximum of 100"),
])
def test_invalid_config_fails_at_parse_time_naming_the_key(tmp_path, patch, key):
    import yaml

    cfg = yaml.safe_load((ROOT / "config" / "smoke.yaml").read_text())
    for top, value in patch.items():
        cfg[top] = {**cfg.get(top, {}), **value}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(cfg))
    proc = _snakemake(ROOT, "-n", "--configfile", str(bad), check=False)
    assert proc.returncode != 0
    text = proc.stdout + proc.stderr
    assert key in text, text[-2000:]
    assert "Job stats" not in text  # refused before any job was planned


def _schema_entries(node, path=""):
    """(path, schema) of every property of the configuration's schema, depth first."""
    if isinstance(node, dict):
        for key, value in node.get("properties", {}).items():
            yield f"{path}.{key}", value
            yield from _schema_entries(value, f"{path}.{key}")
        for key in ("items", "then", "additionalProperties"):
            yield from _schema_entries(node.get(key), path)
        for value in node.get("patternProperties", {}).values():
            yield from _schema_entries(value, f"{path}.*")


def test_the_configs_pid_tunings_are_the_models_range():
    """Every r' the configuration can give is one a scene takes: the schema's bounds are MIN_TUNING and MAX_TUNING
    (a PID the paper's formulas could run but a scene refuses was reported naming the scene's field, not the
    config's)."""
    import yaml

    from impact.model.params import MAX_TUNING, MIN_TUNING

    schema = yaml.safe_load((ROOT / "workflow" / "schemas" / "config.schema.yaml").read_text())
    tunings = {path: (entry.get("items", entry)) for path, entry in _schema_entries(schema)
               if path.rsplit(".", 1)[-1] in ("rp", "pid_tunings")}
    assert len(tunings) >= 5, sorted(tunings)
    for path, bounds in tunings.items():
        assert (bounds.get("minimum"), bounds.get("maximum")) == (MIN_TUNING, MAX_TUNING), path


def test_the_papers_scope_writes_its_own_report_and_archive():
    """make paper after make study must not replace the whole study's report with one that lacks its stages."""
    paper = _snakemake(ROOT, "-n", "all", "archive", "--configfile", "config/config.yaml", "config/paper.yaml").stdout
    study = _snakemake(ROOT, "-n", "all", "archive", "--configfile", "config/config.yaml").stdout
    assert "results/report/paper.html" in paper and "results/report/index.html" not in paper
    assert "results/report/index.html" in study and "paper.html" not in study
    assert re.search(r"results/archive/impact-paper-\S+\.tar\.gz", paper)
    assert re.search(r"results/archive/impact-study-\S+\.tar\.gz", study) and "impact-paper-" not in study


def test_a_misspelt_key_is_named_in_a_few_lines(tmp_path):
    """Not the whole schema after it (two thousand lines): the key, what is wrong, where."""
    bad = tmp_path / "bad.yaml"
    bad.write_text("protocl: {periods: 10}\n")
    proc = _snakemake(ROOT, "-n", "--configfile", "config/smoke.yaml", str(bad), check=False)
    text = proc.stdout + proc.stderr
    assert proc.returncode != 0 and "'protocl' was unexpected" in text
    assert len(text.splitlines()) < 20, text


def test_a_misspelt_key_of_the_rigs_file_is_named_in_a_few_lines(tmp_path):
    rig = tmp_path / "rig.yaml"
    rig.write_text("sensr: {noise_mm: 0.01}\n")
    override = tmp_path / "override.yaml"
    override.write_text(f"validation: {{config: {rig}, smoke: true}}\n")
    proc = _snakemake(ROOT, "-n", "--configfile", "config/smoke.yaml", str(override), check=False)
    text = proc.stdout + proc.stderr
    assert proc.returncode != 0 and f"{rig} (top level)" in text and "'sensr' was unexpected" in text, text[-2000:]
    assert len(text.splitlines()) < 20, text


def test_lint_is_clean():
    proc = _snakemake(ROOT, "--lint")
    assert "Congratulations" in proc.stdout + proc.stderr
