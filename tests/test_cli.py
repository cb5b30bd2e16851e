"""The command line as a newcomer meets it: its version, defaults in every help, one meaning per output key, usage
errors with exit 2, and a drawn run."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest
from PIL import Image

from impact import __version__
from impact.cli import build_parser, main


def _help(command: str) -> str:
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    return sub.format_help()


def test_version_is_the_packages():
    proc = subprocess.run([sys.executable, "-m", "impact.cli", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.strip() == f"impact {__version__}"


def test_every_sub_command_is_one_entry_of_the_dispatch_table_and_loads_only_when_it_runs():
    """The parser's sub-commands are COMMANDS' keys, each a function; the parser, the help and a refused flag load
    the model alone (no numba, no xarray, no stage), and no module of the command line imports inside a function."""
    import ast
    from pathlib import Path

    from impact.cli import COMMANDS, command

    names = next(a for a in build_parser()._actions if a.dest == "command").choices
    assert sorted(names) == sorted(COMMANDS) and all(callable(command(name)) for name in COMMANDS)
    probe = "import sys, impact.cli; print(sorted(m for m in sys.modules if m.split('.')[0] in ('numba', 'xarray') " \
            "or m.startswith('impact.stages')))"
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "[]"
    for path in (Path(__file__).resolve().parents[1] / "src" / "impact" / "cli").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                inner = [n for n in ast.walk(node) if isinstance(n, (ast.Import, ast.ImportFrom))]
                assert not inner, (path.name, node.name)


@pytest.mark.parametrize("command", ["run", "sweep", "quake", "masri", "design", "records"])
def test_every_flag_with_a_default_says_it_in_its_help(command):
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    text = _help(command)
    body = text[text.index("options:"):]
    for action in sub._actions:
        if action.option_strings and action.default not in (None, False, "==SUPPRESS=="):
            flag = action.option_strings[-1]
            # the flag's own entry: "--e" must not find "--equations"
            entry = re.split(rf"\n  {re.escape(flag)}(?=[ ,\n])", body, maxsplit=1)[1].split("\n  -", 1)[0]
            assert "default" in " ".join(entry.split()), (command, flag, entry)


def test_quake_says_why_its_damper_defaults_differ_from_runs():
    assert "earthquake study's larger mass ratio" in " ".join(_help("quake").split())


def test_amplitude_ratio_means_the_same_in_masri_and_run(capsys):
    """X / A_max in both: on the stable 2-EIPC orbit the simulation lands on, the two agree."""
    args = ["--mu", "0.01", "--e", "0.25", "--gap-ratio", "1.6", "--r", "1.0"]
    main(["masri", *args])
    closed = json.loads(capsys.readouterr().out)
    main(["run", *args, "--start", "left"])
    run = json.loads(capsys.readouterr().out)
    upper = closed["upper"]
    assert upper["stable"] and upper["amplitude_ratio"] == pytest.approx(upper["amplitude"] / closed["a_max"])
    assert upper["amplitude_over_static"] == pytest.approx(upper["amplitude"] / 0.096)
    # the peak amplitude of the orbit against the run's sqrt(2) RMS: close, not equal, on the same scale
    assert run["amplitude_ratio"] == pytest.approx(upper["amplitude_ratio"], rel=0.05)


@pytest.mark.parametrize("argv, words", [
    (["sweep", "--r-step", "0.5"], "a sweep needs two or more"),
    (["sweep", "--r-min", "1.0", "--r-max", "1.0"], "a sweep needs two or more"),
    (["verify-archive", "no/such/archive.tar.gz"], "no such archive"),
    (["run", "--damper", "cid", "--rp", "1.0"], "--rp is only for --damper pid"),
    (["quake", "--record", "elcentro", "--damper", "tmd", "--gap-m", "0.1"], "--gap-m is not used by --damper tmd"),
    (["quake", "--record", "elcentro", "--plot", "x.png"], "--plot draws a damper"),
    (["run", "--e", "2"], "--e"),
    # a PID tuned beyond what a scene takes is refused by its own flag, not by the scene's field (tuning)
    (["run", "--damper", "pid", "--rp", "500"], "argument --rp: 500.0 is out of range: allowed [0.1, 100"),
    # what a new user tripped on: a plot in a format matplotlib does not draw, a dataset that is not netCDF or
    # goes to a folder that does not exist, a record in none of the forms --record takes
    (["quake", "--record", "elcentro", "--damper", "cid", "--gap-m", "0.05", "--plot", "x.txt"], ".png, .pdf, .svg"),
    (["sweep", "--out", "s.txt"], "must end in .nc"),
    (["sweep", "--out", "/nonexistent/dir/s.nc"], "does not exist"),
    (["quake", "--record", "no-such-record"], "fema-farfield:ID:a|b"),
    (["quake", "--record", "elcentro", "--max-events", "5"], "argument --max-events: 5 is out of range"),
])
def test_usage_errors_exit_2_naming_the_flag(argv, words, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2 and words in capsys.readouterr().err


@pytest.mark.parametrize("argv", [
    ["run", "--damper", "cid", "--gap-ratio", "1.6", "--start", "left", "--periods", "60", "--average-from", "30"],
    ["quake", "--record", "elcentro", "--pga-g", "0.3", "--storeys", "2", "--damper", "cid", "--gap-m", "0.05",
     "--duration-s", "8"],
])
def test_plot_draws_the_run_it_reports(argv, tmp_path, capsys):
    path = tmp_path / "run.png"
    main([*argv, "--plot", str(path)])
    out = json.loads(capsys.readouterr().out)
    with Image.open(path) as image:
        assert image.format == "PNG" and image.size[0] > 800
    impacts = out["impacts"] if "impacts" in out else out["diagnostics"]["impacts"]
    assert impacts > 0
    # the reported run is the drawn one: it ran on the scene loop, the one that samples
    assert out.get("loop", "scene") == "scene"


def test_quake_tunes_a_tmd_for_the_building_unless_told(capsys):
    """A TMD given no tuning or damping is the study's design for the building and its mass (Den Hartog on the
    first mode), which lowers the roof's peak under the README's own example, where an untuned, undamped one
    (f = 1, no damping: the old defaults) raised it."""
    from impact.closed_form.tmd import tuned_for
    from impact.model.building import Building

    quake = ["quake", "--record", "fema-farfield:12:a", "--storeys", "3"]
    peaks = {}
    for name, flags in (("bare", []), ("designed", ["--damper", "tmd"]),
                        ("untuned", ["--damper", "tmd", "--tuning", "1", "--damping", "0"])):
        main([*quake, *flags])
        out = json.loads(capsys.readouterr().out)
        peaks[name] = out["peak_roof_displacement_m"]
        if name == "designed":
            design = tuned_for(Building.uniform(3, 1.0, 0.02), 0.02)
            assert out["dampers"][0]["tuning"] == design.tuning and out["dampers"][0]["damping"] == design.damping
    assert peaks["designed"] < peaks["bare"] < peaks["untuned"], peaks


def test_quake_gives_a_tmd_end_stops_that_hold_its_stroke(capsys):
    """--stroke-limit-m puts stops in a TMD's travel: a stroke of 2.2 m without them (3 storeys, T1 = 2 s, El
    Centro at 0.8 g) is held to the limit by strikes, the energy still balancing; a CID's walls are its limit."""
    quake = ["quake", "--record", "elcentro", "--storeys", "3", "--period-s", "2", "--pga-g", "0.8", "--damper", "tmd"]
    main(quake)
    free = json.loads(capsys.readouterr().out)
    main([*quake, "--stroke-limit-m", "0.3", "--e", "0.5"])
    stopped = json.loads(capsys.readouterr().out)
    assert free["peak_damper_stroke_m"][0] > 2.0 and free["impacts"] == 0
    assert 0.3 * (1 - 1e-9) <= stopped["peak_damper_stroke_m"][0] <= 0.3 * (1 + 1e-9)
    assert stopped["impacts"] > 0 and stopped["dampers"][0]["stroke_limit"] == 0.3
    assert abs(stopped["diagnostics"]["energy_residual"]) < 1e-9
    with pytest.raises(SystemExit):
        main(["quake", "--record", "elcentro", "--damper", "cid", "--gap-m", "0.1", "--stroke-limit-m", "0.3"])
    assert "--stroke-limit-m is not used by --damper cid" in capsys.readouterr().err


def _quake(capsys, *flags) -> dict:
    main(["quake", "--record", "elcentro", "--duration-s", "8", *flags])
    return json.loads(capsys.readouterr().out)


def test_quake_stops_a_run_past_its_event_budget_and_says_why(capsys):
    """Issue 42: an e = 1 CID in a nanometre gap, which would strike millions of times, stops at --max-events and
    names the budget, the unit and the wall in its diagnostics."""
    out = _quake(capsys, "--damper", "cid", "--gap-m", "1e-9", "--e", "1", "--max-events", "1000")
    d = out["diagnostics"]
    assert d["stopped_by"] == "event budget" and d["stop_unit"] == 0 and d["stop_event"] == "wall"
    assert d["event_cap_reached"] and out["impacts"] == 1000


def test_quake_takes_a_building_floor_by_floor(capsys):
    """Given floor by floor with the uniform building's own masses and stiffnesses, it is the same building: the
    same run to the bit; a non-uniform one is refused by name when only half given or mixed with --storeys."""
    from impact.model.building import Building

    uniform = Building.uniform(3, 0.8, 0.02, floor_mass=2e5)
    by_floor = ["--masses-kg", ",".join(repr(float(m)) for m in uniform.masses),
                "--storey-stiffness-n-per-m", ",".join(repr(float(k)) for k in uniform.storey_stiffness)]
    a = _quake(capsys, "--storeys", "3", "--period-s", "0.8", "--floor-mass-kg", "2e5", "--damper", "cid",
               "--gap-m", "0.05")
    b = _quake(capsys, *by_floor, "--damper", "cid", "--gap-m", "0.05")
    assert a["peak_roof_displacement_m"] == b["peak_roof_displacement_m"] and a["impacts"] == b["impacts"]
    softer_top = _quake(capsys, "--masses-kg", "2e5,2e5,2e5", "--storey-stiffness-n-per-m", "4e8,3e8,1e8")
    assert softer_top["building"]["storey_stiffness"] == [4e8, 3e8, 1e8]
    for bad, named in ((by_floor[:2], "go together"), ([*by_floor, "--storeys", "3"], "--storeys")):
        with pytest.raises(SystemExit):
            main(["quake", "--record", "elcentro", *bad])
        assert named in capsys.readouterr().err


def test_quake_compares_with_the_bare_building_and_writes_its_series(tmp_path, capsys):
    bare = _quake(capsys, "--storeys", "2")
    series = tmp_path / "run.csv"
    out = _quake(capsys, "--storeys", "2", "--damper", "pid", "--gap-m", "0.04", "--units", "2", "--compare-bare",
                 "--series", str(series))
    for key, value in out["bare"].items():
        # the same bare run but for the series' samples inside record steps, which those steps take by the rows
        assert value == pytest.approx(bare[key], rel=1e-12)
        assert out["ratio_to_bare"][key] == pytest.approx(out[key] / value, rel=1e-15)
    import pandas as pd

    table = pd.read_csv(series)
    assert list(table.columns) == ["t_s", "floor1_m", "floor2_m", "damper1_unit1_stroke_m", "damper1_unit2_stroke_m"]
    # the samples lie under the certified peaks, and come close to them (samples every T1/50)
    peak = out["peak_roof_displacement_m"]
    assert 0.95 * peak <= table.floor2_m.abs().max() <= peak * (1 + 1e-12)
    assert table[["damper1_unit1_stroke_m", "damper1_unit2_stroke_m"]].abs().max().max() <= 0.02 * (1 + 1e-9)


def test_sweep_out_writes_the_dataset_and_prints_its_summary(tmp_path, capsys):
    import xarray as xr

    path = tmp_path / "s.nc"
    main(["sweep", "--r-min", "0.9", "--r-max", "1.1", "--r-step", "0.1", "--periods", "60", "--average-from", "30",
          "--out", str(path)])
    out = json.loads(capsys.readouterr().out)
    assert out["out"] == str(path) and "amplitude" not in out and "r" not in out and "X_m" in out
    with xr.open_dataset(path) as ds:
        assert ds.sizes["freq_ratio"] == 3
