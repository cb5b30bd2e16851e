"""The one writer: atomic files, self-describing datasets."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from impact.outputs.files import atomic_path, undescribed_variables, write_dataset


def _dataset():
    return xr.Dataset({"amplitude": (("r",), np.linspace(1.0, 2.0, 4), {"units": "1", "long_name": "amplitude"})},
                      coords={"r": ("r", np.linspace(0.9, 1.1, 4), {"units": "1", "long_name": "frequency ratio"}),
                              "member": ("member", np.arange(2), {"units": "1", "long_name": "member"}),
                              "start": ("start", ["centre", "left"], {"long_name": "start of the damper mass"})})


def test_a_dataset_is_written_self_describing_and_round_trips(tmp_path):
    path = write_dataset(_dataset(), tmp_path / "d.nc")
    with xr.open_dataset(path) as back:
        back.load()
    assert back.attrs["Conventions"].startswith("CF-1.")
    assert {"source", "code_version", "git_commit", "date_created"} <= set(back.attrs)
    np.testing.assert_array_equal(back["amplitude"].values, _dataset()["amplitude"].values)
    # CF 1.8: coordinate variables without _FillValue, no 64-bit integers
    assert all("_FillValue" not in back[c].encoding or back[c].encoding["_FillValue"] is None for c in back.coords)
    assert back["member"].dtype == np.int32


def test_an_undescribed_variable_is_refused_by_name_and_nothing_is_written(tmp_path):
    ds = _dataset().assign(bare=("r", np.zeros(4)))
    assert undescribed_variables(ds) == ["bare"]
    with pytest.raises(ValueError, match="bare"):
        write_dataset(ds, tmp_path / "d.nc")
    assert list(tmp_path.iterdir()) == []


def test_a_failed_write_leaves_neither_the_target_nor_a_temporary_file(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("killed")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]
