"""One run of the study as a single verifiable archive.

``build_archive`` writes ``results/archive/impact-study-<commit>.tar.gz``: the
given result files (datasets, figures, tables, report, configuration) under
one top-level folder, with

- ``MANIFEST.json``: path, size and sha256 of every other file in the archive,
  and for each netCDF file a ``content_sha256``: a hash of its decoded values,
  coordinates and attributes (``netcdf_content_sha256``).  The bytes of an
  HDF5 file are not reproducible between two writes of the same data; the
  content hash is, so it is what to compare between two runs;
- ``MANIFEST.sha256``: the sha256 of ``MANIFEST.json``'s bytes, so an edit of
  the manifest alone is seen too;
- ``ENVIRONMENT.json``: the study's package versions
  (``impact.outputs.provenance.package_versions``), every installed distribution
  (a ``pip freeze``-like list from ``importlib.metadata``), Python and platform;
- ``CITATION.cff``: Citation File Format 1.2.0, citing this run (version,
  commit, date) and the paper it reproduces;
- ``config.json``: the run's configuration, canonical JSON (its sha256 is the
  report's configuration hash).

``verify_archive`` re-checks every entry against the manifest and returns the
paths that differ (empty if the archive is intact); ``verify_main`` is the
command line (exit 0 if intact, 1 with each differing path on stderr).

The archive is written atomically (a temporary file in the target folder,
then a rename).  Members are sorted, owned by uid/gid 0 and stamped with one
time (``SOURCE_DATE_EPOCH`` if set, else the build time), so the same files
give the same archive bytes under a fixed ``SOURCE_DATE_EPOCH``.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import gzip
import hashlib
import io
import json
import os
import platform
import sys
import tarfile
import tempfile
import zlib
from collections.abc import Iterable, Mapping
from pathlib import Path, PurePosixPath

import numpy as np
import xarray as xr
import yaml

from impact import __version__
from impact.outputs.files import atomic_path
from impact.outputs.provenance import git_state, package_versions
from impact.outputs.report import canonical_json, config_hash

MANIFEST = "MANIFEST.json"
MANIFEST_DIGEST = "MANIFEST.sha256"
ENVIRONMENT = "ENVIRONMENT.json"
CITATION = "CITATION.cff"
CONFIG = "config.json"
GENERATED = (MANIFEST, MANIFEST_DIGEST, ENVIRONMENT, CITATION, CONFIG)
MANIFEST_FORMAT = "impact-study-manifest/1"
NETCDF_SUFFIXES = (".nc", ".nc4", ".netcdf")
_CHUNK = 1 << 20

PAPER = {
    "type": "article",
    "title": "Classical impact damper and pendulum impact damper for potential civil engineering application",
    "authors": [
        {"family-names": "Chua", "given-names": "George Sy"},
        {"family-names": "Pacheco", "given-names": "Benito M."},
        {"family-names": "Fujino", "given-names": "Yozo"},
        {"family-names": "Ito", "given-names": "Manabu"},
    ],
}


# --------------------------------------------------------------------------- hashes


def file_sha256(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(_CHUNK), b""):
            h.update(block)
    return h.hexdigest()


def _canon_value(v):
    """An attribute value as plain JSON data, with its type where numpy gives one."""
    if isinstance(v, np.ndarray):
        return {"dtype": v.dtype.str.lstrip("<>=|"), "shape": list(v.shape), "values": _canon_value(v.tolist())}
    if isinstance(v, np.generic):
        return {"dtype": v.dtype.str.lstrip("<>=|"), "value": _canon_value(v.item())}
    if isinstance(v, bytes):
        return {"bytes": v.hex()}
    if isinstance(v, (list, tuple)):
        return [_canon_value(x) for x in v]
    if isinstance(v, float):
        return repr(v) if not np.isfinite(v) else v
    if isinstance(v, (str, int, bool)) or v is None:
        return v
    return str(v)


def _canon_attrs(attrs: Mapping) -> dict:
    return {str(k): _canon_value(v) for k, v in sorted(attrs.items(), key=lambda kv: str(kv[0]))}


def _array_bytes(values: np.ndarray) -> tuple[str, bytes]:
    """A canonical byte string for an array's values: little-endian, C order, one NaN."""
    a = np.asarray(values)
    if a.dtype.kind in "fc":
        a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))
        parts = a.view(a.real.dtype.newbyteorder("<")) if a.dtype.kind == "c" else a
        parts = np.where(np.isnan(parts), np.array(np.nan, dtype=parts.dtype), parts)
        return a.dtype.str, np.ascontiguousarray(parts, dtype=parts.dtype.newbyteorder("<")).tobytes()
    if a.dtype.kind in "iub":
        a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))
        return a.dtype.str, a.tobytes()
    if a.dtype.kind in "mM":
        return a.dtype.str.lstrip("<>="), np.ascontiguousarray(a.view("i8"), dtype="<i8").tobytes()
    # strings, bytes and objects: their text, as JSON
    items = [x.decode("utf-8", "surrogateescape") if isinstance(x, bytes) else x for x in a.ravel().tolist()]
    return "text", canonical_json([_canon_value(x) for x in items]).encode("utf-8")


def dataset_content_sha256(ds) -> str:
    """sha256 of an xarray Dataset's decoded content, independent of its storage.

    Covered: the global attributes; and for every variable and coordinate, in name order,
    its name, dimensions, shape, dtype kind, attributes and values (little-endian, C order,
    every NaN the same).  Not covered: the storage (chunking, compression, HDF5 layout) and
    the encoding attributes xarray moves out of ``attrs`` when it decodes (``_FillValue``,
    ``scale_factor``, ``units`` of times...): their effect is in the decoded values.
    """
    h = hashlib.sha256()

    def put(obj):
        blob = canonical_json(obj).encode("utf-8")
        h.update(len(blob).to_bytes(8, "little"))
        h.update(blob)

    put({"attrs": _canon_attrs(ds.attrs), "dims": {str(k): int(v) for k, v in sorted(ds.sizes.items())}})
    for name in sorted(map(str, ds.variables)):
        var = ds.variables[name]
        values = var.values
        kind, blob = _array_bytes(values)
        put({"name": name, "dims": list(map(str, var.dims)), "shape": list(values.shape), "dtype": kind,
             "coord": name in ds.coords, "attrs": _canon_attrs(var.attrs)})
        h.update(len(blob).to_bytes(8, "little"))
        h.update(blob)
    return h.hexdigest()


def netcdf_content_sha256(path) -> str:
    """The content hash of a netCDF file, decoded with xarray (``dataset_content_sha256``)."""

    with xr.open_dataset(path, engine="netcdf4", cache=False) as ds:
        ds.load()
        return dataset_content_sha256(ds)


def _is_netcdf(name: str) -> bool:
    return name.lower().endswith(NETCDF_SUFFIXES)


# --------------------------------------------------------------------------- environment and citation


def environment() -> dict:
    from importlib.metadata import distributions

    dists = {}
    for d in distributions():
        name = d.metadata["Name"]
        if name:
            dists[name] = d.version
    return {
        "packages": package_versions(),
        "distributions": [f"{n}=={v}" for n, v in sorted(dists.items(), key=lambda kv: kv[0].lower())],
        "python": sys.version,
        "implementation": platform.python_implementation(),
        "platform": platform.platform(),
        "machine": platform.machine(),
    }


def citation_cff(citation: Mapping | None, commit: str, date: str) -> dict:
    """CITATION.cff (1.2.0) content: this run, citing the paper; ``citation`` keys override."""

    cff = {
        "cff-version": "1.2.0",
        "message": "If you use these results, please cite them as below, and the paper they reproduce.",
        "type": "dataset",
        "title": "Impact dampers for civil structures: a reproducible study (results of one run)",
        "authors": [{"name": "impact-dampers study contributors"}],
        "version": str(__version__),
        "commit": commit,
        "date-released": date,
        "abstract": ("Results of a reproduction of the parametric study of Chua, Pacheco, Fujino and Ito on the "
                     "classical and pendulum impact dampers and the tuned mass damper, with an exact "
                     "event-driven simulator."),
        "keywords": ["impact damper", "pendulum impact damper", "tuned mass damper", "reproducibility"],
        "references": [dict(PAPER)],
    }
    for key, value in (citation or {}).items():
        cff[key] = value
    return cff


def _yaml(obj) -> str:

    return yaml.safe_dump(obj, sort_keys=False, allow_unicode=True, default_flow_style=False, width=100)


# --------------------------------------------------------------------------- building


def archive_name(commit: str, dirty: str | bool = "no", scope: str = "study") -> str:
    """``impact-<scope>-<commit>.tar.gz`` (scope: the whole study, or the paper's part of it alone); ``-dirty``
    is added for a tree with uncommitted changes."""
    dirty = dirty if isinstance(dirty, bool) else str(dirty) == "yes"
    safe = "".join(c if c.isalnum() or c in "._-" else "_" for c in (commit or "unknown"))
    return f"impact-{scope}-{safe}{'-dirty' if dirty else ''}.tar.gz"


def _epoch() -> int:
    value = os.environ.get("SOURCE_DATE_EPOCH")
    if value:
        try:
            return int(value)
        except ValueError:
            pass
    return int(_dt.datetime.now(_dt.timezone.utc).timestamp())


def _collect(root: Path, include: Iterable) -> dict[str, Path]:
    """Archive path (relative to root, POSIX) -> file, for the files and folders given."""
    root = root.resolve()
    files: dict[str, Path] = {}
    for item in include:
        path = Path(item)
        path = path if path.is_absolute() else root / path
        if not path.exists():
            raise FileNotFoundError(f"{item}: no such file to archive")
        found = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
        for f in found:
            try:
                rel = f.resolve().relative_to(root)
            except ValueError:  # e.g. a --configfile kept elsewhere
                rel = PurePosixPath("external", f.name)
            name = rel.as_posix()
            if name in files and files[name].resolve() != f.resolve():
                raise ValueError(f"{name}: two different files would have this path in the archive")
            if name in GENERATED:
                raise ValueError(f"{name}: the archive writes this file itself")
            if any(part.startswith(".") and part.endswith(".tmp") for part in rel.parts):
                continue
            files[name] = f
    return dict(sorted(files.items()))


def _add(tar: tarfile.TarFile, name: str, data: bytes | None, path: Path | None, mtime: int) -> None:
    info = tarfile.TarInfo(name)
    info.mtime, info.mode, info.uid, info.gid, info.uname, info.gname = mtime, 0o644, 0, 0, "", ""
    if path is not None:
        info.size = path.stat().st_size
        with open(path, "rb") as fh:
            tar.addfile(info, fh)
    else:
        info.size = len(data)
        tar.addfile(info, io.BytesIO(data))


def build_archive(out_tar_gz, root, include: list, config: Mapping | None, citation: Mapping | None = None
                  ) -> Path:
    """Write the archive of one run (see the module's docstring); return its path.

    root: the folder the included paths are relative to (the workflow's folder); include:
    files or folders under it (results, figures, tables, report, configuration files);
    config: the run's configuration; citation: keys of CITATION.cff to set (commit, date, ...).
    """

    out = Path(out_tar_gz)
    root = Path(root)
    files = _collect(root, include)
    state = git_state()
    citation = dict(citation or {})
    commit = str(citation.get("commit") or state["git_commit"])
    epoch = _epoch()
    created = _dt.datetime.fromtimestamp(epoch, _dt.timezone.utc)
    citation.setdefault("commit", commit)
    citation.setdefault("date-released", created.date().isoformat())
    prefix = out.name.removesuffix(".gz").removesuffix(".tar").removesuffix(".tgz")

    generated = {
        CONFIG: (canonical_json(config if config is not None else {}) + "\n").encode("utf-8"),
        ENVIRONMENT: (json.dumps(environment(), indent=1, sort_keys=True) + "\n").encode("utf-8"),
        CITATION: ("# Citation File Format 1.2.0 (https://citation-file-format.github.io)\n"
                   + _yaml(citation_cff(citation, commit, citation["date-released"]))).encode("utf-8"),
    }
    entries = []
    for name, path in files.items():
        entry = {"path": name, "size": path.stat().st_size, "sha256": file_sha256(path)}
        if _is_netcdf(name):
            entry["content_sha256"] = netcdf_content_sha256(path)
        entries.append(entry)
    for name, data in generated.items():
        entries.append({"path": name, "size": len(data), "sha256": hashlib.sha256(data).hexdigest()})
    entries.sort(key=lambda e: e["path"])
    manifest = {
        "format": MANIFEST_FORMAT,
        "name": prefix,
        "code_version": __version__,
        "git_commit": commit,
        "git_dirty": state["git_dirty"],
        "created": created.isoformat(timespec="seconds"),
        "config_sha256": config_hash(config if config is not None else {}),
        "content_sha256_definition": ("sha256 of the decoded values, coordinates and attributes of a netCDF file "
                           "(impact.outputs.archive.netcdf_content_sha256); compare it between runs, not the file bytes"),
        "files": entries,
    }
    manifest_bytes = (json.dumps(manifest, indent=1, sort_keys=True) + "\n").encode("utf-8")
    digest = f"{hashlib.sha256(manifest_bytes).hexdigest()}  {MANIFEST}\n".encode("ascii")

    with atomic_path(out) as tmp, open(tmp, "wb") as raw, \
            gzip.GzipFile(filename="", mode="wb", fileobj=raw, mtime=epoch, compresslevel=6) as gz, \
            tarfile.open(fileobj=gz, mode="w", format=tarfile.PAX_FORMAT) as tar:
        _add(tar, f"{prefix}/{MANIFEST}", manifest_bytes, None, epoch)
        _add(tar, f"{prefix}/{MANIFEST_DIGEST}", digest, None, epoch)
        for name, data in generated.items():
            _add(tar, f"{prefix}/{name}", data, None, epoch)
        for name, path in files.items():
            _add(tar, f"{prefix}/{name}", None, path, epoch)
    return out


# --------------------------------------------------------------------------- verifying


def _safe_name(name: str) -> bool:
    p = PurePosixPath(name)
    return not p.is_absolute() and ".." not in p.parts and "\\" not in name


def check_archive(path) -> list[tuple[str, str]]:
    """Every difference between an archive and its manifest, as (path, reason) pairs.

    Checked: the manifest's own digest; each listed file's presence, size, sha256 and, for
    netCDF, the content hash recomputed from the extracted file; files in the archive the
    manifest does not list; duplicate, unsafe and non-regular members.
    """
    path = Path(path)
    problems: list[tuple[str, str]] = []
    try:
        tar = tarfile.open(path, mode="r:gz")
    except (OSError, tarfile.TarError, EOFError) as exc:
        return [(str(path), f"not a readable .tar.gz archive: {exc}")]
    with tar:
        try:
            members = tar.getmembers()
        except (OSError, tarfile.TarError, EOFError, zlib.error) as exc:
            return [(str(path), f"archive is damaged: {exc}")]
        manifests = [m for m in members
                     if PurePosixPath(m.name).name == MANIFEST and len(PurePosixPath(m.name).parts) <= 2]
        if len(manifests) != 1:
            return [(MANIFEST, "missing from the archive" if not manifests else "more than one in the archive")]
        mman = manifests[0]
        prefix = str(PurePosixPath(mman.name).parent)
        prefix = "" if prefix == "." else prefix + "/"

        def read(member) -> bytes:
            fh = tar.extractfile(member)
            return fh.read() if fh is not None else b""

        try:
            manifest_bytes = read(mman)
            manifest = json.loads(manifest_bytes)
            listed = {e["path"]: e for e in manifest["files"]}
            repeated = len(manifest["files"]) - len(listed)
        except (ValueError, KeyError, TypeError, OSError, tarfile.TarError, EOFError, zlib.error) as exc:
            return [(MANIFEST, f"unreadable: {exc}")]

        if repeated:
            problems.append((MANIFEST, f"lists {repeated} path(s) more than once"))
        by_name: dict[str, list[tarfile.TarInfo]] = {}
        for m in members:
            if m.isdir():
                continue
            if not m.name.startswith(prefix):
                problems.append((m.name, "outside the archive's folder"))
                continue
            by_name.setdefault(m.name[len(prefix):], []).append(m)

        digests = by_name.pop(MANIFEST_DIGEST, [])
        by_name.pop(MANIFEST, None)
        want = hashlib.sha256(manifest_bytes).hexdigest()
        if len(digests) != 1:
            problems.append((MANIFEST, f"{MANIFEST_DIGEST} missing or repeated"))
        else:
            try:
                got = read(digests[0]).decode("ascii").split()[0]
            except (UnicodeDecodeError, IndexError, OSError, tarfile.TarError, EOFError, zlib.error):
                got = ""
            if got != want:
                problems.append((MANIFEST, f"does not match {MANIFEST_DIGEST} (edited after the archive was built)"))

        for name, entry in sorted(listed.items()):
            found = by_name.pop(name, [])
            if not found:
                problems.append((name, "listed in the manifest, missing from the archive"))
                continue
            if len(found) > 1:
                problems.append((name, f"{len(found)} members with this name"))
            member = found[-1]
            if not member.isfile():
                problems.append((name, "not a regular file in the archive"))
                continue
            if not _safe_name(name):
                problems.append((name, "unsafe path"))
            problems.extend(_check_member(tar, member, name, entry))
        for name in sorted(by_name):
            problems.append((name, "in the archive, not in the manifest"))
    return problems


def _check_member(tar, member, name, entry) -> list[tuple[str, str]]:
    out = []
    h = hashlib.sha256()
    size = 0
    tmp = None
    try:
        fh = tar.extractfile(member)
        netcdf = "content_sha256" in entry or _is_netcdf(name)
        sink = tempfile.NamedTemporaryFile(suffix=".nc", delete=False) if netcdf else None
        tmp = sink.name if sink else None
        for block in iter(lambda: fh.read(_CHUNK), b""):
            h.update(block)
            size += len(block)
            if sink:
                sink.write(block)
        if sink:
            sink.close()
    except (OSError, tarfile.TarError, EOFError, zlib.error) as exc:
        if tmp:
            Path(tmp).unlink(missing_ok=True)
        return [(name, f"unreadable in the archive: {exc}")]
    try:
        if size != entry.get("size"):
            out.append((name, f"size {size} != manifest {entry.get('size')}"))
        if h.hexdigest() != entry.get("sha256"):
            out.append((name, "sha256 differs from the manifest"))
        if tmp:
            if "content_sha256" not in entry:
                out.append((name, "netCDF file without a content_sha256 in the manifest"))
            else:
                try:
                    content = netcdf_content_sha256(tmp)
                except Exception as exc:  # noqa: BLE001 - any decoding failure is a finding
                    out.append((name, f"netCDF content unreadable: {type(exc).__name__}: {exc}"))
                else:
                    if content != entry["content_sha256"]:
                        out.append((name, "netCDF content (values, coordinates, attributes) differs from the manifest"))
    finally:
        if tmp:
            Path(tmp).unlink(missing_ok=True)
    return out


def verify_archive(path) -> list[str]:
    """Paths of the archive entries that differ from its manifest (empty: the archive is intact)."""
    return sorted({name for name, _ in check_archive(path)})


def verify_main(argv=None) -> int:
    """``impact verify-archive FILE``: exit 0 if every entry matches the manifest, else 1.

    Prints a JSON summary on stdout when intact; otherwise each differing path, with the
    reason, on stderr.
    """
    ap = argparse.ArgumentParser(prog="impact verify-archive",
                                 description="Re-check a study archive against its MANIFEST.json.")
    ap.add_argument("file", help="the archive, results/archive/impact-study-<commit>.tar.gz")
    args = ap.parse_args(argv)
    problems = check_archive(args.file)
    if problems:
        for name, reason in problems:
            print(f"{name}: {reason}", file=sys.stderr)
        return 1
    json.dump(archive_summary(args.file), sys.stdout, indent=1)
    sys.stdout.write("\n")
    return 0


def archive_summary(path) -> dict:
    """What an intact archive holds, from its manifest (for the command line's JSON output)."""
    with tarfile.open(path, "r:gz") as tar:
        man = next(m for m in tar.getmembers()
                   if PurePosixPath(m.name).name == MANIFEST and len(PurePosixPath(m.name).parts) <= 2)
        manifest = json.loads(tar.extractfile(man).read())
    return {"archive": str(path), "ok": True, "files": len(manifest["files"]),
            "git_commit": manifest.get("git_commit"), "git_dirty": manifest.get("git_dirty"),
            "created": manifest.get("created"), "config_sha256": manifest.get("config_sha256")}


# --------------------------------------------------------------------------- Snakemake glue


def snakemake_main(smk) -> Path:
    """Body of the ``archive`` rule's script: every named input is archived, by its path relative to the
    workflow's folder; params.citation (optional) sets CITATION.cff keys."""
    inp = smk.input
    include = []
    for key in inp.keys():
        value = getattr(inp, key)
        include.extend([value] if isinstance(value, str) else list(value))
    root = Path(getattr(smk.params, "root", ".") or ".")
    citation = dict(getattr(smk.params, "citation", {}) or {})
    return build_archive(smk.output[0], root, include, smk.config, citation)


if __name__ == "__main__":
    sys.exit(verify_main())
