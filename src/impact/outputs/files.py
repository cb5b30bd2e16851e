"""Every file the study writes goes through here: atomically, and every dataset self-describing.

A result is written to a temporary file beside its target and renamed over
it only once complete, so a killed job never leaves a partial or corrupt file
behind.  write_dataset adds CF conventions and the provenance (code version,
git commit) to a dataset and refuses one whose variables lack a long_name and
units (or, for a categorical variable, CF flag attributes), naming them.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from impact.outputs.provenance import attributes

if TYPE_CHECKING:  # xarray only for the annotations: a job that writes no dataset does not import it
    import xarray as xr

#: the CF version every dataset declares, the one the tests check them against (compliance-checker cf:1.8)
CONVENTIONS = "CF-1.8"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def publish(tmp, path) -> None:
    """Flush a finished temporary file to disk, give it ordinary permissions and move it into place."""
    with open(tmp, "rb") as fh:
        os.fsync(fh.fileno())
    os.chmod(tmp, 0o666 & ~_umask())
    os.replace(tmp, path)


@contextlib.contextmanager
def atomic_path(path, suffix: str | None = None):
    """A temporary path beside `path`, moved over it when the block succeeds and removed when it fails.

    suffix: of the temporary file (default `.tmp`); writers that infer the format from the name
    (matplotlib) need the target's own suffix.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix if suffix is not None else ".tmp",
                               dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_text_atomic(path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def write_json_atomic(path, obj) -> None:
    write_text_atomic(path, json.dumps(obj, indent=1, sort_keys=True) + "\n")


def write_csv_atomic(path, frame) -> None:
    write_text_atomic(path, frame.to_csv(index=False))


def undescribed_variables(ds: xr.Dataset) -> list[str]:
    """Variables and coordinates without a long_name (or standard_name) and units (or CF flags)."""
    missing = []
    for name, var in {**ds.coords, **ds.data_vars}.items():
        named = "long_name" in var.attrs or "standard_name" in var.attrs
        text = var.dtype.kind in "OSU"  # labels: a name is enough, they have no unit
        measured = text or "units" in var.attrs or "flag_values" in var.attrs or "flag_meanings" in var.attrs
        if not (named and measured):
            missing.append(str(name))
    return missing


def flag(long_name: str, unset: str, set_: str) -> dict:
    """CF attributes of a 0/1 variable: what each value means, and no unit."""
    return {"long_name": long_name, "flag_values": np.array([0, 1], dtype=np.int8),
            "flag_meanings": f"{unset} {set_}"}


def as_integers(ds: xr.Dataset, names, missing: int | None = None) -> xr.Dataset:
    """Counts and flags held as floats (a table's columns) as 32-bit integers, attributes kept.

    missing: the value written for NaN (a run that failed has no count), declared as the variable's CF
    _FillValue so that a reader gets NaN back; None refuses a NaN."""
    for name in names:
        if name not in ds:
            continue
        values = np.asarray(ds[name].values, dtype=float)
        absent = np.isnan(values)
        if (absent.any() and missing is None) or np.any(values[~absent] != np.round(values[~absent])):
            raise ValueError(f"{name}: a count or flag must be a whole number everywhere")
        attrs = dict(ds[name].attrs)
        if "flag_values" in attrs:  # CF: a flag's values have the variable's type
            attrs["flag_values"] = np.asarray(attrs["flag_values"], dtype=np.int32)
        if absent.any():
            attrs["_FillValue"] = np.int32(missing)
        ds[name] = (ds[name].dims, np.where(absent, missing if missing is not None else 0, values).astype(np.int32),
                    attrs)
    return ds


def describe(ds: xr.Dataset, config: dict | None = None) -> xr.Dataset:
    """The dataset with CF conventions, the code's provenance, a history line and (when given, unless the
    dataset has its own) the configuration it was made from in its global attributes."""
    ds = ds.copy()
    prov = attributes()
    ds.attrs = {**ds.attrs, **{k: v for k, v in prov.items() if k not in ds.attrs}}
    if config is not None and "config" not in ds.attrs:
        ds.attrs["config"] = json.dumps(config, sort_keys=True)
    line = f"{prov['date_created']}: written by {prov['source']}, commit {prov['git_commit']}"
    ds.attrs["history"] = "\n".join(filter(None, (ds.attrs.get("history"), line)))
    ds.attrs["Conventions"] = CONVENTIONS
    return ds


def _cf_types(ds: xr.Dataset) -> xr.Dataset:
    """64-bit integers (not a CF 1.8 type) as 32-bit ones, where every value fits."""
    for name, var in {**ds.coords, **ds.data_vars}.items():
        if var.dtype == np.int64 and (var.size == 0 or np.abs(var.values).max() < 2**31):
            ds[name] = var.astype(np.int32)
    return ds


def write_dataset(ds: xr.Dataset, path, config: dict | None = None) -> Path:
    """Write a self-describing, compressed netCDF atomically (see the module doc).

    config: what the job's results depend on (its params), kept as JSON in the global attribute `config`."""
    missing = undescribed_variables(ds)
    if missing:
        raise ValueError(f"{path}: variables {', '.join(missing)} lack long_name and units (or CF flag "
                         "attributes); every dataset the study writes must describe each of its variables")
    ds = _cf_types(describe(ds, config))
    encoding = {name: {"zlib": True, "complevel": 4} for name in ds.data_vars if ds[name].dtype.kind in "fiu"}
    for name in ds.coords:
        # CF: a coordinate variable has no missing values, so no _FillValue
        encoding.setdefault(name, {})["_FillValue"] = None
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, encoding=encoding, engine="netcdf4")
    return Path(path)
