"""Masri's closed form drawn without simulation: the stability chart over (r, d) and both roots along r."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr

from impact.closed_form.masri import BRANCHES, classify, masri_2eipc, orbit_rms_amplitude
from impact.model.params import a_max


def stability_chart(mu, e, beta, force_ratio, r_values, d_values) -> np.ndarray:
    """Class of the best root on an (r, d/(F0/K)) grid (masri.classify: 0 none .. 3 stable)."""
    out = np.zeros((len(d_values), len(r_values)), dtype=np.int8)
    for j, r in enumerate(r_values):
        for i, dx in enumerate(d_values):
            out[i, j] = classify(mu, e, beta, r, dx * force_ratio, force_ratio=force_ratio)
    return out


def branches(mu, e, beta, force_ratio, gap_ratio, r_values) -> pd.DataFrame:
    """sqrt(2)*RMS amplitude of both closed-form roots along r at one gap (NaN where inadmissible)."""
    gap = gap_ratio * a_max(beta, force_ratio)
    rows = []
    for r in r_values:
        sol = masri_2eipc(mu, e, beta, r, gap, force_ratio=force_ratio)
        for name in BRANCHES:
            root = sol[name]
            amp = (orbit_rms_amplitude(root, mu, e, beta, r, gap, force_ratio) / force_ratio
                   if root["admissible"] else math.nan)
            rows.append({"r": r, "root": name, "stable": bool(root["stable"]), "amplitude_over_xst": amp})
    return pd.DataFrame(rows)


def chart_dataset(cfg: dict, beta: float, force_ratio: float) -> xr.Dataset:
    r = np.linspace(cfg["r"]["min"], cfg["r"]["max"], int(cfg["r"]["n"]))
    d = np.linspace(cfg["d_over_xst"]["max"] / cfg["d_over_xst"]["n"], cfg["d_over_xst"]["max"],
                    int(cfg["d_over_xst"]["n"]))
    classes = np.stack([stability_chart(cfg["mu"], e, beta, force_ratio, r, d) for e in cfg["e"]])
    ds = xr.Dataset(
        {"class": (("e", "d_over_xst", "r"), classes, {
            "long_name": "best 2-EIPC root of the closed form", "flag_values": np.array([0, 1, 2, 3], dtype=np.int8),
            "flag_meanings": "no_solution roots_none_admissible admissible_unstable admissible_stable"})},
        coords={"e": ("e", np.asarray(cfg["e"], float), {"units": "1", "long_name": "coefficient of restitution"}),
                "d_over_xst": ("d_over_xst", d, {"units": "1", "long_name": "total clearance over F0/K"}),
                "r": ("r", r, {"units": "1", "long_name": "frequency ratio"})})
    ds.attrs.update(mu=cfg["mu"], beta=beta, force_ratio=force_ratio)
    return ds
