"""Experiment records: the on-disk format, a validating loader and an atomic writer.

One record per file.  The format is specified in ``docs/experiment-data.md``;
in short, a CSV file with a ``# key: value`` header block::

    # format_version: 1
    # kind: free_decay
    # synthetic: false
    # sample_rate_hz: 100
    # units: mm
    # damper: none
    # x0_mm: 20
    t_s,x
    0.00,20.003
    0.01,19.998
    ...

Time histories (``free_decay``, ``forced_sweep_point``) have the columns
``t_s, x`` (optionally ``s``, the damper's displacement relative to the
structure, which only a simulation provides); drop tests have the columns
``drop_height_cm, rebound_height_cm``, one drop per row.

:func:`load_measurement` refuses anything it cannot vouch for with a
:class:`MeasurementError` whose message names the file, the field and, for data
rows, the row number (1-based, counted from the first data row; the file line
number follows in parentheses).  :func:`write_measurement` validates before writing
and writes atomically (temporary file in the same folder, then rename).

A netCDF variant (``.nc``) with the same fields as global attributes and the
same columns as variables along one dimension is read and written by the same
two functions; it goes through the same validation.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import netCDF4
import numpy as np

from impact.model.kinds import impact_kinds, kind_of
from impact.outputs.files import atomic_path

FORMAT_VERSION = 1
KINDS = ("free_decay", "forced_sweep_point", "drop_test")
TIME_KINDS = ("free_decay", "forced_sweep_point")
UNITS = {"m": 1.0, "mm": 1e-3}  # metres per record unit
DAMPERS = ("none", *impact_kinds())  # a rig carries no damper or an impact damper (model.kinds)

TIME_COLUMNS = ("t_s", "x")
OPTIONAL_TIME_COLUMNS = ("s",)
DROP_COLUMNS = ("drop_height_cm", "rebound_height_cm")

# Tolerances of the sampling check: the median step must match 1/sample_rate_hz
# to SAMPLE_RATE_RTOL, and no single step may exceed GAP_FACTOR / sample_rate_hz
# (a dropout) -- the analysis assumes uniform sampling.
SAMPLE_RATE_RTOL = 0.01
GAP_FACTOR = 1.5
FORCING_RTOL = 1e-3


class MeasurementError(ValueError):
    """A record that cannot be accepted; the message names the field (and row)."""


# ----------------------------------------------------------------------------
# header schema
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Field:
    type: str  # "str", "float", "int", "bool"
    doc: str
    choices: tuple[str, ...] | None = None
    lo: float | None = None  # inclusive lower bound
    hi: float | None = None  # inclusive upper bound
    lo_open: bool = False
    hi_open: bool = False


HEADER_FIELDS: dict[str, _Field] = {
    "format_version": _Field("int", "format version, 1", lo=1, hi=1),
    "kind": _Field("str", "record kind", choices=KINDS),
    "synthetic": _Field("bool", "true for generated (simulated) data, false for measurements"),
    "sample_rate_hz": _Field("float", "sampling rate of t_s, x [Hz]", lo=0.0, lo_open=True),
    "units": _Field("str", "unit of x (and s)", choices=tuple(UNITS)),
    "damper": _Field("str", "damper on the structure during the run", choices=DAMPERS),
    "mu": _Field("float", "mass ratio m/M of the damper ball (drop test: ball / struck body)",
                 lo=0.0, hi=1.0, hi_open=True),
    "gap_mm": _Field("float", "total clearance d [mm]", lo=0.0, lo_open=True),
    "rp": _Field("float", "pendulum tuning ratio r' = omega_p/omega", lo=0.0, lo_open=True),
    "wall": _Field("str", "wall / lining material, e.g. steel, rubber_1.0mm, cork_3.0mm"),
    "e": _Field("float", "coefficient of restitution used (simulated) or assumed", lo=0.0, hi=1.0),
    "r": _Field("float", "forcing frequency ratio Omega/omega", lo=0.0, lo_open=True),
    "forcing_hz": _Field("float", "forcing frequency [Hz]", lo=0.0, lo_open=True),
    "structure_hz": _Field("float", "natural frequency of the bare structure [Hz]", lo=0.0, lo_open=True),
    "x0_mm": _Field("float", "initial displacement of a free decay [mm]"),
    "ball_diameter_mm": _Field("float", "ball diameter [mm]", lo=0.0, lo_open=True),
    "noise_rms": _Field("float", "sensor noise rms, in record units (known or assumed)", lo=0.0),
    "seed": _Field("int", "random seed of a synthetic record", lo=0),
    "id": _Field("str", "record identifier"),
    "date": _Field("str", "date of the run"),
    "source": _Field("str", "where the data come from (rig, script, figure)"),
    "notes": _Field("str", "free text"),
}

_KEY_RE = re.compile(r"^[a-z_][a-z0-9_]*$")


def _required_fields(header: Mapping[str, Any]) -> list[str]:
    """The fields required for this header (depends on kind and damper)."""
    req = ["kind", "synthetic"]
    kind = header.get("kind")
    if kind in TIME_KINDS:
        req += ["sample_rate_hz", "units", "damper"]
        if kind == "free_decay":
            req.append("x0_mm")
        else:
            req.append("r")
        damper = header.get("damper")
        if damper in impact_kinds():
            req += ["mu", "gap_mm"]
            if kind_of(damper).spring:
                req.append("rp")
    elif kind == "drop_test":
        req += ["mu", "wall"]
    return req


def _parse_value(key: str, raw: Any) -> Any:
    """Typed value of header field ``key`` from a string (CSV) or attribute (netCDF)."""
    spec = HEADER_FIELDS.get(key)
    if spec is None:
        allowed = ", ".join(HEADER_FIELDS)
        raise MeasurementError(f"header field {key!r} is unknown (allowed: {allowed})")
    if isinstance(raw, np.generic):
        raw = raw.item()
    if spec.type == "str":
        value = str(raw).strip()
        if not value:
            raise MeasurementError(f"header field {key} is empty")
        if "\n" in value or "\r" in value:
            raise MeasurementError(f"header field {key} contains a line break")
        if spec.choices is not None and value not in spec.choices:
            raise MeasurementError(f"header field {key}: {value!r} is not one of {', '.join(spec.choices)}")
        return value
    if spec.type == "bool":
        if isinstance(raw, bool):
            return raw
        if isinstance(raw, (int, np.integer)) and raw in (0, 1):
            return bool(raw)
        text = str(raw).strip().lower()
        if text in ("true", "false"):
            return text == "true"
        raise MeasurementError(f"header field {key}: {raw!r} is not true or false")
    # numbers
    if isinstance(raw, bool):
        raise MeasurementError(f"header field {key}: {raw!r} is not a number")
    try:
        if spec.type == "int":
            if isinstance(raw, (int, np.integer)):
                value = int(raw)
            else:
                text = str(raw).strip()
                if not re.fullmatch(r"[+-]?\d+", text):
                    raise ValueError
                value = int(text)
        else:
            value = float(str(raw).strip()) if not isinstance(raw, (int, float)) else float(raw)
    except ValueError:
        kind = "an integer" if spec.type == "int" else "a number"
        raise MeasurementError(f"header field {key}: {raw!r} is not {kind}") from None
    if not math.isfinite(value):
        raise MeasurementError(f"header field {key}: {raw!r} is not finite")
    lo, hi = spec.lo, spec.hi
    if (lo is not None and (value <= lo if spec.lo_open else value < lo)) or (
        hi is not None and (value >= hi if spec.hi_open else value > hi)
    ):
        lb = "(" if spec.lo_open else "["
        rb = ")" if spec.hi_open else "]"
        lo_s = "-inf" if lo is None else f"{lo:g}"
        hi_s = "inf" if hi is None else f"{hi:g}"
        raise MeasurementError(f"header field {key} = {value!r} is out of range {lb}{lo_s}, {hi_s}{rb}")
    return value


def validate_header(raw: Mapping[str, Any]) -> dict[str, Any]:
    """Typed, checked header from raw values; raises :class:`MeasurementError`."""
    header = {key: _parse_value(key, value) for key, value in raw.items()}
    if "kind" not in header:
        raise MeasurementError("header field kind missing")
    for key in _required_fields(header):
        if key not in header:
            why = f"kind {header['kind']}"
            if key in ("mu", "gap_mm", "rp") and "damper" in header:
                why += f", damper {header['damper']}"
            raise MeasurementError(f"header field {key} missing (required for {why})")
    kind = header["kind"]
    if kind == "drop_test":
        for key in ("sample_rate_hz", "units", "r", "forcing_hz", "x0_mm", "gap_mm", "rp", "damper"):
            if key in header:
                raise MeasurementError(f"header field {key} does not apply to kind drop_test")
        if "e" in header and not header["synthetic"]:
            raise MeasurementError("header field e: a measured drop test determines e; "
                              "give e only for a synthetic drop test (the value it was generated with)")
    else:
        if kind == "free_decay" and ("r" in header or "forcing_hz" in header):
            raise MeasurementError("header field r / forcing_hz does not apply to kind free_decay")
        if kind == "forced_sweep_point" and "x0_mm" in header:
            raise MeasurementError("header field x0_mm does not apply to kind forced_sweep_point")
        if header["damper"] == "none":
            for key in ("mu", "gap_mm", "rp", "wall", "e"):
                if key in header:
                    raise MeasurementError(f"header field {key} does not apply to damper none")
        else:
            if "wall" not in header and "e" not in header:
                raise MeasurementError(f"header field wall missing (damper {header['damper']} needs "
                                  "the wall material or e)")
            if not kind_of(header["damper"]).spring and "rp" in header:
                raise MeasurementError(f"header field rp does not apply to damper {header['damper']} (it has no "
                                       "spring)")
        if all(k in header for k in ("r", "forcing_hz", "structure_hz")):
            expected = header["r"] * header["structure_hz"]
            if abs(header["forcing_hz"] - expected) > FORCING_RTOL * expected:
                raise MeasurementError(
                    f"header field forcing_hz = {header['forcing_hz']!r} disagrees with "
                    f"r * structure_hz = {expected!r}")
    return header


# ----------------------------------------------------------------------------
# the record
# ----------------------------------------------------------------------------


def _entry(part: str, key: str) -> property:
    """A read-only attribute for one entry of a record's header or columns."""
    return property(lambda record: getattr(record, part)[key], doc=f"the record's {part} entry {key!r}")


@dataclass(frozen=True)
class Measurement:
    """One validated record: typed header and float64 columns (read-only arrays)."""

    header: dict[str, Any]
    columns: dict[str, np.ndarray]
    path: Path | None = field(default=None, compare=False)

    kind = _entry("header", "kind")
    synthetic = _entry("header", "synthetic")
    t = _entry("columns", "t_s")

    @property
    def x(self) -> np.ndarray:
        """Structure displacement in the record's ``units``."""
        return self.columns["x"]

    def x_in(self, unit: str) -> np.ndarray:
        """Structure displacement converted to ``unit`` ('m' or 'mm')."""
        return self._convert("x", unit)

    def s_in(self, unit: str) -> np.ndarray:
        """Damper displacement relative to the structure, in ``unit`` (synthetic records)."""
        if "s" not in self.columns:
            raise KeyError("record has no s column")
        return self._convert("s", unit)

    def _convert(self, name: str, unit: str) -> np.ndarray:
        if unit not in UNITS:
            raise ValueError(f"unit {unit!r} is not one of {', '.join(UNITS)}")
        return self.columns[name] * (UNITS[self.header["units"]] / UNITS[unit])

    drop_height_cm = _entry("columns", "drop_height_cm")
    rebound_height_cm = _entry("columns", "rebound_height_cm")


def _where(row: int, line: int | None) -> str:
    return f"row {row}" + (f" (line {line})" if line is not None else "")


def _validate_columns(header: Mapping[str, Any], names: list[str],
                      data: Mapping[str, np.ndarray], lines: np.ndarray | None) -> dict[str, np.ndarray]:
    """Check column names and values; ``lines`` maps data rows to file lines."""
    kind = header["kind"]
    if kind in TIME_KINDS:
        required, optional = TIME_COLUMNS, OPTIONAL_TIME_COLUMNS
    else:
        required, optional = DROP_COLUMNS, ()
    expected_text = ", ".join(required) + (f" [, {', '.join(optional)}]" if optional else "")
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise MeasurementError(f"column {dup[0]!r} appears twice (expected columns {expected_text})")
    for name in names:
        if name not in required and name not in optional:
            raise MeasurementError(f"column {name!r} not allowed for kind {kind} (expected columns {expected_text})")
    for name in required:
        if name not in names:
            raise MeasurementError(f"column {name} missing (expected columns {expected_text})")
    if tuple(names[: len(required)]) != required:
        raise MeasurementError(f"columns in wrong order: {', '.join(names)} (expected {expected_text})")

    def line_of(i: int) -> int | None:
        return None if lines is None else int(lines[i])

    cols = {}
    n = None
    for name in names:
        arr = np.asarray(data[name], dtype=float)
        if arr.ndim != 1:
            raise MeasurementError(f"column {name} is not one-dimensional")
        if n is None:
            n = arr.size
        elif arr.size != n:
            raise MeasurementError(f"column {name} has {arr.size} values, expected {n}")
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            i = int(bad[0])
            what = "NaN" if np.isnan(arr[i]) else "infinite"
            raise MeasurementError(f"{_where(i + 1, line_of(i))}: {name} is {what}")
        cols[name] = arr
    n = n or 0

    if kind in TIME_KINDS:
        if n < 3:
            raise MeasurementError(f"time history has {n} rows, needs at least 3")
        t = cols["t_s"]
        dt = np.diff(t)
        bad = np.flatnonzero(dt <= 0.0)
        if bad.size:
            i = int(bad[0]) + 1
            raise MeasurementError(f"{_where(i + 1, line_of(i))}: t_s is not increasing "
                              f"({float(t[i])!r} after {float(t[i - 1])!r})")
        fs = header["sample_rate_hz"]
        step = 1.0 / fs
        med = float(np.median(dt))
        if abs(med - step) > SAMPLE_RATE_RTOL * step:
            raise MeasurementError(f"header field sample_rate_hz = {fs!r} disagrees with the t_s spacing "
                              f"(median step {med!r} s, i.e. {1.0 / med:.6g} Hz)")
        gaps = np.flatnonzero(dt > GAP_FACTOR * step)
        if gaps.size:
            i = int(gaps[0]) + 1
            raise MeasurementError(f"{_where(i + 1, line_of(i))}: gap in t_s ({float(dt[i - 1])!r} s after "
                              f"{float(t[i - 1])!r}, sample step {step!r} s)")
    else:
        if n < 1:
            raise MeasurementError("drop test has no rows")
        hd, hr = cols["drop_height_cm"], cols["rebound_height_cm"]
        for i in range(n):
            if hd[i] <= 0.0:
                raise MeasurementError(f"{_where(i + 1, line_of(i))}: drop_height_cm must be > 0, got {float(hd[i])!r}")
            if hr[i] < 0.0:
                raise MeasurementError(f"{_where(i + 1, line_of(i))}: rebound_height_cm must be >= 0, got {float(hr[i])!r}")
            if hr[i] > hd[i]:
                raise MeasurementError(f"{_where(i + 1, line_of(i))}: rebound_height_cm ({float(hr[i])!r}) exceeds "
                                  f"drop_height_cm ({float(hd[i])!r})")
    for arr in cols.values():
        arr.flags.writeable = False
    return cols


def make_measurement(header: Mapping[str, Any], columns: Mapping[str, Iterable[float]],
                path: str | os.PathLike | None = None) -> Measurement:
    """A validated :class:`Measurement` from a header mapping and columns (name -> values).

    Header values may be strings (as read from a file) or typed values; the
    column order is that of ``columns``.
    """
    hdr = validate_header(header)
    names = list(columns)
    data = {name: np.array(list(v) if not isinstance(v, np.ndarray) else v, dtype=float)
            for name, v in columns.items()}
    cols = _validate_columns(hdr, names, data, None)
    return Measurement(hdr, cols, None if path is None else Path(path))


# ----------------------------------------------------------------------------
# CSV
# ----------------------------------------------------------------------------


def _parse_csv(text: str) -> tuple[dict[str, str], list[str], dict[str, np.ndarray], np.ndarray]:
    lines = text.splitlines()
    raw: dict[str, str] = {}
    i = 0
    # header block: leading '#' lines ('##' lines and bare '#' are comments)
    while i < len(lines) and (lines[i].lstrip().startswith("#") or not lines[i].strip()):
        line = lines[i].strip()
        i += 1
        if not line or line.startswith("##") or line == "#":
            continue
        body = line[1:].strip()
        if ":" not in body:
            raise MeasurementError(f"line {i}: header line is not '# key: value': {line!r}")
        key, value = body.split(":", 1)
        key = key.strip()
        if not _KEY_RE.match(key):
            raise MeasurementError(f"line {i}: header key {key!r} is not a lower-case identifier")
        if key in raw:
            raise MeasurementError(f"line {i}: header field {key} given twice")
        raw[key] = value.strip()
    if i >= len(lines):
        raise MeasurementError("no column line after the header block")
    col_line = i + 1
    names = [c.strip() for c in lines[i].split(",")]
    if any(not n for n in names):
        raise MeasurementError(f"line {col_line}: empty column name in {lines[i]!r}")
    for n in names:
        try:
            float(n)
        except ValueError:
            continue
        raise MeasurementError(f"line {col_line}: column line missing (found numbers {lines[i]!r}); "
                          f"expected column names")
    i += 1
    rows: list[list[float]] = []
    line_no: list[int] = []
    ncol = len(names)
    for j in range(i, len(lines)):
        line = lines[j].strip()
        if not line:
            continue
        row = len(rows) + 1
        where = _where(row, j + 1)
        if line.startswith("#"):
            raise MeasurementError(f"{where}: header line after the data start")
        cells = [c.strip() for c in line.split(",")]
        if len(cells) != ncol:
            raise MeasurementError(f"{where}: expected {ncol} values ({', '.join(names)}), got {len(cells)}")
        vals = []
        for name, cell in zip(names, cells):
            try:
                vals.append(float(cell))
            except ValueError:
                raise MeasurementError(f"{where}: {name} is not a number ({cell!r})") from None
        rows.append(vals)
        line_no.append(j + 1)
    arr = np.array(rows, dtype=float).reshape(len(rows), ncol)
    data = {name: arr[:, k] for k, name in enumerate(names)}
    return raw, names, data, np.array(line_no, dtype=int)


def _format_header_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _csv_text(record: Measurement) -> str:
    out = [f"# {key}: {_format_header_value(value)}" for key, value in record.header.items()]
    names = list(record.columns)
    out.append(",".join(names))
    cols = [record.columns[n].tolist() for n in names]
    out.extend(",".join(repr(v) for v in row) for row in zip(*cols))
    return "\n".join(out) + "\n"


# ----------------------------------------------------------------------------
# netCDF
# ----------------------------------------------------------------------------


def _read_netcdf(path: Path) -> tuple[dict[str, Any], list[str], dict[str, np.ndarray]]:

    try:
        ds = netCDF4.Dataset(path, "r")
    except OSError as exc:
        raise MeasurementError(f"cannot read netCDF: {exc}") from None
    with ds:
        raw = {k: ds.getncattr(k) for k in ds.ncattrs()}
        names = list(ds.variables)
        data = {}
        for name in names:
            var = ds.variables[name]
            var.set_auto_mask(False)
            data[name] = np.asarray(var[:], dtype=float)
    return raw, names, data


def _write_netcdf(tmp: str, record: Measurement) -> None:

    with netCDF4.Dataset(tmp, "w", format="NETCDF4") as ds:
        n = next(iter(record.columns.values())).size
        ds.createDimension("row", n)
        for key, value in record.header.items():
            ds.setncattr(key, _format_header_value(value) if isinstance(value, bool) else value)
        for name, arr in record.columns.items():
            var = ds.createVariable(name, "f8", ("row",))
            var[:] = arr


# ----------------------------------------------------------------------------
# public I/O
# ----------------------------------------------------------------------------


def load_measurement(path: str | os.PathLike) -> Measurement:
    """Read and validate one record (``.csv`` or ``.nc``).

    Raises :class:`MeasurementError` whose message starts with the path and names
    the offending field, column or data row.
    """
    path = Path(path)
    try:
        if path.suffix == ".nc":
            raw, names, data = _read_netcdf(path)
            lines = None
        else:
            try:
                text = path.read_text(encoding="utf-8")
            except UnicodeDecodeError as exc:
                raise MeasurementError(f"not UTF-8 text ({exc.reason})") from None
            raw, names, data, lines = _parse_csv(text)
        header = validate_header(raw)
        cols = _validate_columns(header, names, data, lines)
    except MeasurementError as exc:
        raise MeasurementError(f"{path}: {exc}") from None
    return Measurement(header, cols, path)


def load_measurements(folder: str | os.PathLike, kind: str | None = None,
                 patterns: tuple[str, ...] = ("*.csv", "*.nc")) -> list[Measurement]:
    """All records under ``folder`` (recursively), sorted by path; optionally one kind."""
    folder = Path(folder)
    if not folder.is_dir():
        raise MeasurementError(f"{folder}: not a folder")
    if kind is not None and kind not in KINDS:
        raise ValueError(f"kind {kind!r} is not one of {', '.join(KINDS)}")
    paths = sorted({p for pat in patterns for p in folder.rglob(pat) if not p.name.startswith(".")})
    records = [load_measurement(p) for p in paths]
    return [r for r in records if kind is None or r.kind == kind]


def write_measurement(path: str | os.PathLike, record: Measurement | tuple[Mapping[str, Any], Mapping[str, Any]]) -> Path:
    """Validate and write ``record`` to ``path`` atomically (``.nc`` -> netCDF, else CSV).

    ``record`` is a :class:`Measurement` or a ``(header, columns)`` pair.  The file
    is first written to a temporary file in the target folder and then renamed
    over ``path``, so readers never see a partial record.
    """
    path = Path(path)
    if not isinstance(record, Measurement):
        header, columns = record
        record = make_measurement(header, columns)
    else:  # re-validate: a Measurement may have been built by hand
        record = make_measurement(record.header, record.columns)
    with atomic_path(path) as tmp:
        if path.suffix == ".nc":
            _write_netcdf(str(tmp), record)
        else:
            tmp.write_text(_csv_text(record), encoding="utf-8", newline="\n")
    return path
