"""The archive of a run: manifest, environment, citation; verification finds any changed entry."""

from __future__ import annotations

import hashlib
import io
import json
import re
import tarfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml

import impact
from impact.outputs import archive
from impact.outputs.files import write_dataset

MARKER = 1234.5678901234  # a value that occurs once in the uncompressed dataset's bytes
CONFIG = {"structure": {"beta": 0.0048}, "protocol": {"periods": 40}, "figures": {"fig08": {}}}
COMMIT = "0123456789abcdef0123456789abcdef01234567"


def _dataset(values=None) -> xr.Dataset:
    amp = np.array([[0.5, 0.25, np.nan], [1.0, MARKER, 0.75]]) if values is None else values
    return xr.Dataset(
        {"amplitude": (("start", "freq_ratio"), amp, {"units": "model_unit", "long_name": "amplitude"}),
         "ipc_class": (("start", "freq_ratio"), np.array([[1, 2, -1], [0, 2, 3]], dtype=np.int8),
                       {"flag_values": np.array([-1, 0, 1, 2, 3], dtype=np.int8), "long_name": "IPC class"})},
        coords={"start": ("start", np.array(["centre", "left"], dtype=object), {"long_name": "start"}),
                "freq_ratio": ("freq_ratio", [0.9, 1.0, 1.1], {"units": "1", "long_name": "frequency ratio"})},
        attrs={"title": "test sweep", "param_mu": 0.01, "config": json.dumps(CONFIG)})


def _plain_copy(src: Path, dst: Path, **kw) -> None:
    """The same content as src (with the writer's attributes), stored uncompressed."""
    with xr.open_dataset(src) as ds:
        ds.load().drop_encoding().to_netcdf(dst, engine="netcdf4", **kw)


@pytest.fixture
def tree(tmp_path) -> Path:
    root = tmp_path / "work"
    res = root / "results"
    write_dataset(_dataset(), res / "sweeps" / "cid_a.nc")  # compressed, as the pipeline writes them
    _plain_copy(res / "sweeps" / "cid_a.nc", res / "sweeps" / "plain.nc")  # a value's bytes are findable
    (res / "figures").mkdir(parents=True)
    (res / "figures" / "fig08.png").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 4)
    (res / "tables").mkdir(parents=True)
    (res / "tables" / "paper_vs_reproduced.csv").write_text("figure,paper,reproduced\n8,0.32,0.314\n")
    (res / "report").mkdir(parents=True)
    (res / "report" / "index.html").write_text("<!DOCTYPE html><title>r</title>\n")
    (root / "config").mkdir()
    (root / "config" / "smoke.yaml").write_text(yaml.safe_dump(CONFIG))
    return root


def _build(tree: Path) -> Path:
    out = tree / "results" / "archive" / archive.archive_name(COMMIT, "no")
    return archive.build_archive(out, tree, ["results/sweeps", "results/figures", "results/tables",
                                             "results/report", "config/smoke.yaml"], CONFIG, {"commit": COMMIT})


def _members(path: Path) -> list[tuple[tarfile.TarInfo, bytes]]:
    with tarfile.open(path, "r:gz") as tar:
        return [(m, tar.extractfile(m).read()) for m in tar.getmembers()]


def _repack(src: Path, dest: Path, edit) -> Path:
    """Copy an archive, passing each member's (name, bytes) through edit (None drops it)."""
    with tarfile.open(dest, "w:gz") as tar:
        for info, data in _members(src):
            new = edit(info.name, data)
            if new is None:
                continue
            info.size = len(new)
            tar.addfile(info, io.BytesIO(new))
    return dest


def _member(path: Path, suffix: str) -> bytes:
    return next(data for info, data in _members(path) if info.name.endswith(suffix))


def test_archive_contents_manifest_environment_citation(tree):
    out = _build(tree)
    assert out.name == f"impact-study-{COMMIT}.tar.gz"
    assert sorted(p.name for p in out.parent.iterdir()) == [out.name]  # written atomically
    names = [info.name for info, _ in _members(out)]
    prefix = f"impact-study-{COMMIT}/"
    assert all(n.startswith(prefix) for n in names)
    inside = sorted(n[len(prefix):] for n in names)
    assert inside == sorted(["MANIFEST.json", "MANIFEST.sha256", "ENVIRONMENT.json", "CITATION.cff", "config.json",
                             "config/smoke.yaml", "results/figures/fig08.png", "results/report/index.html",
                             "results/sweeps/cid_a.nc", "results/sweeps/plain.nc",
                             "results/tables/paper_vs_reproduced.csv"])

    manifest = json.loads(_member(out, "MANIFEST.json"))
    files = {e["path"]: e for e in manifest["files"]}
    assert set(files) == set(inside) - {"MANIFEST.json", "MANIFEST.sha256"}
    for rel in ("results/figures/fig08.png", "results/sweeps/cid_a.nc", "config/smoke.yaml"):
        data = (tree / rel).read_bytes()
        assert files[rel]["size"] == len(data)
        assert files[rel]["sha256"] == hashlib.sha256(data).hexdigest()
    # netCDF: a content hash, the same for the compressed and the plain file of the same data
    assert "content_sha256" not in files["results/figures/fig08.png"]
    assert files["results/sweeps/cid_a.nc"]["content_sha256"] == files["results/sweeps/plain.nc"]["content_sha256"]
    assert files["results/sweeps/cid_a.nc"]["sha256"] != files["results/sweeps/plain.nc"]["sha256"]
    assert manifest["git_commit"] == COMMIT
    assert manifest["config_sha256"] == hashlib.sha256(
        json.dumps(CONFIG, sort_keys=True, separators=(",", ":")).encode()).hexdigest()
    assert json.loads(_member(out, "/config.json")) == CONFIG
    assert _member(out, "MANIFEST.sha256").decode().split()[0] == hashlib.sha256(
        _member(out, "MANIFEST.json")).hexdigest()

    env = json.loads(_member(out, "ENVIRONMENT.json"))
    assert env["packages"]["numpy"] == np.__version__ and "python" in env["packages"]
    assert f"numpy=={np.__version__}" in env["distributions"]

    cff = yaml.safe_load(_member(out, "CITATION.cff"))
    assert cff["cff-version"] == "1.2.0"
    assert cff["message"] and cff["title"]
    assert cff["authors"] == [{"name": "impact-dampers study contributors"}]
    assert cff["version"] == impact.__version__ and cff["commit"] == COMMIT
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", cff["date-released"])  # a string, as the schema wants
    paper = cff["references"][0]
    assert paper["type"] == "article" and "pendulum impact damper" in paper["title"].lower()
    assert [a["family-names"] for a in paper["authors"]] == ["Chua", "Pacheco", "Fujino", "Ito"]

    assert archive.verify_archive(out) == []


def test_verify_main_exit_codes(tree, tmp_path, capsys):
    out = _build(tree)
    assert archive.verify_main([str(out)]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["ok"] is True and summary["files"] == 9
    bad = _repack(out, tmp_path / "bad.tar.gz", lambda n, d: d.replace(b"0.314", b"0.315")
                  if n.endswith("paper_vs_reproduced.csv") else d)
    assert archive.verify_main([str(bad)]) == 1
    err = capsys.readouterr().err
    assert "results/tables/paper_vs_reproduced.csv: sha256 differs from the manifest" in err
    assert archive.verify_main([str(tmp_path / "missing.tar.gz")]) == 1


def test_flipped_byte_in_a_result_file_is_found(tree, tmp_path):
    out = _build(tree)

    def flip(name, data):
        if name.endswith("results/figures/fig08.png"):
            data = bytearray(data)
            data[100] ^= 0x01
            return bytes(data)
        return data

    bad = _repack(out, tmp_path / "flipped.tar.gz", flip)
    assert archive.verify_archive(bad) == ["results/figures/fig08.png"]
    reasons = dict(archive.check_archive(bad))
    assert reasons["results/figures/fig08.png"] == "sha256 differs from the manifest"  # same size


def test_changed_data_value_in_a_netcdf_file_is_found(tree, tmp_path):
    out = _build(tree)
    old = np.float64(MARKER).tobytes()
    new = np.float64(MARKER + 1.0).tobytes()

    def edit(name, data):
        if name.endswith("results/sweeps/plain.nc"):
            assert data.count(old) == 1
            return data.replace(old, new)
        return data

    bad = _repack(out, tmp_path / "value.tar.gz", edit)
    assert archive.verify_archive(bad) == ["results/sweeps/plain.nc"]
    reasons = [r for p, r in archive.check_archive(bad) if p == "results/sweeps/plain.nc"]
    assert "sha256 differs from the manifest" in reasons
    assert any(r.startswith("netCDF content") and "differs" in r for r in reasons), reasons


def test_tampered_manifest_is_found(tree, tmp_path):
    out = _build(tree)
    manifest = json.loads(_member(out, "MANIFEST.json"))

    # a file's recorded hash changed: both the manifest and that file are named
    m1 = json.loads(json.dumps(manifest))
    entry = next(e for e in m1["files"] if e["path"] == "results/tables/paper_vs_reproduced.csv")
    entry["sha256"] = "0" * 64
    bad = _repack(out, tmp_path / "m1.tar.gz", lambda n, d: (json.dumps(m1, indent=1, sort_keys=True) + "\n").encode()
                  if n.endswith("/MANIFEST.json") else d)
    assert archive.verify_archive(bad) == ["MANIFEST.json", "results/tables/paper_vs_reproduced.csv"]

    # only a field that names no file changed: still found, by the manifest's own digest
    m2 = dict(manifest, git_commit="f" * 40)
    bad = _repack(out, tmp_path / "m2.tar.gz", lambda n, d: (json.dumps(m2, indent=1, sort_keys=True) + "\n").encode()
                  if n.endswith("/MANIFEST.json") else d)
    assert archive.verify_archive(bad) == ["MANIFEST.json"]

    # no manifest at all
    bad = _repack(out, tmp_path / "m3.tar.gz", lambda n, d: None if n.endswith("/MANIFEST.json") else d)
    assert archive.verify_archive(bad) == ["MANIFEST.json"]


def test_missing_and_extra_entries_are_found(tree, tmp_path):
    out = _build(tree)
    bad = _repack(out, tmp_path / "missing.tar.gz", lambda n, d: None if n.endswith("cid_a.nc") else d)
    assert archive.check_archive(bad) == [
        ("results/sweeps/cid_a.nc", "listed in the manifest, missing from the archive")]

    prefix = f"impact-study-{COMMIT}/"
    extra = tmp_path / "extra.tar.gz"
    with tarfile.open(extra, "w:gz") as tar:
        for info, data in _members(out):
            tar.addfile(info, io.BytesIO(data))
        info = tarfile.TarInfo(prefix + "results/tables/smuggled.csv")
        info.size = 3
        tar.addfile(info, io.BytesIO(b"a,b"))
    assert archive.check_archive(extra) == [("results/tables/smuggled.csv", "in the archive, not in the manifest")]

    junk = tmp_path / "junk.tar.gz"
    junk.write_bytes(b"not an archive")
    assert archive.verify_archive(junk) == [str(junk)]


def test_content_hash_sees_values_attributes_and_coordinates_not_storage(tmp_path):
    base = archive.dataset_content_sha256(_dataset())
    write_dataset(_dataset(), tmp_path / "a.nc")
    _plain_copy(tmp_path / "a.nc", tmp_path / "b.nc", format="NETCDF4_CLASSIC")
    assert archive.netcdf_content_sha256(tmp_path / "a.nc") == archive.netcdf_content_sha256(tmp_path / "b.nc")

    def changed(edit):
        ds = _dataset()
        edit(ds)
        return archive.dataset_content_sha256(ds)

    assert changed(lambda ds: ds["amplitude"].values.__setitem__((0, 0), 0.5000000000000001)) != base
    assert changed(lambda ds: ds.attrs.__setitem__("date_created", "2030-01-01")) != base
    assert changed(lambda ds: ds["amplitude"].attrs.__setitem__("units", "m")) != base
    assert changed(lambda ds: ds.__setitem__("freq_ratio", ("freq_ratio", [0.9, 1.0 + 1e-15, 1.1], {"units": "1"}))) \
        != base
    assert changed(lambda ds: ds["freq_ratio"].attrs.__setitem__("units", "Hz")) != base
    assert changed(lambda ds: ds.__setitem__("start", ("start", np.array(["centre", "right"], dtype=object)))) != base
    assert changed(lambda ds: ds["ipc_class"].attrs.__setitem__(
        "flag_values", np.array([-1, 0, 1, 2, 4], dtype=np.int8))) != base
    # every NaN is the same NaN
    assert changed(lambda ds: ds["amplitude"].values.__setitem__((0, 2), -np.nan)) == base


def test_deterministic_under_source_date_epoch(tree, tmp_path, monkeypatch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    include = ["results/sweeps", "results/tables", "config/smoke.yaml"]
    a = archive.build_archive(tmp_path / "a" / "x.tar.gz", tree, include, CONFIG, {"commit": COMMIT})
    b = archive.build_archive(tmp_path / "b" / "x.tar.gz", tree, include, CONFIG, {"commit": COMMIT})
    assert a.read_bytes() == b.read_bytes()
    cff = yaml.safe_load(_member(a, "CITATION.cff"))
    assert cff["date-released"] == "2023-11-14"


def test_snakemake_script_entry_archives_every_named_input(tree, monkeypatch):
    from types import SimpleNamespace

    class Named(dict):
        def __getattr__(self, key):
            try:
                return self[key]
            except KeyError:
                raise AttributeError(key) from None

    monkeypatch.chdir(tree)
    out = tree / "results" / "archive" / "x.tar.gz"
    smk = SimpleNamespace(
        input=Named(sweeps=["results/sweeps/cid_a.nc"], report="results/report/index.html",
                    config=["config/smoke.yaml"]),
        output=[str(out)], params=Named(), config=CONFIG)
    assert archive.snakemake_main(smk) == out
    manifest = json.loads(_member(out, "MANIFEST.json"))
    assert [e["path"] for e in manifest["files"]] == ["CITATION.cff", "ENVIRONMENT.json", "config.json",
                                                      "config/smoke.yaml", "results/report/index.html",
                                                      "results/sweeps/cid_a.nc"]
    assert archive.verify_archive(out) == []
