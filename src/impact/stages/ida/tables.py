"""The incremental dynamic analysis's collected dataset, verdicts and fragility fits (no simulation)."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import xarray as xr
from scipy import optimize, stats

from impact.model.scene import DAMPER_KINDS
from impact.model.suites import GROUPS, record_of
from impact.stages.ida.plan import AT_LIMIT, DESIGN_KEYS
from impact.stages.resampling import cluster_draws

#: the bare building's measures kept beside the damped ones in the collected dataset
BARE_KEPT = ("drift_ratio", "peak_roof", "peak_accel", "energy_residual")


def collect(bare: dict, dampers: dict) -> xr.Dataset:
    """Every building and damper in one dataset: damped measures over (building, damper, mass_ratio, motion, level),
    their drift ratio over the bare building's, the bare measures and each motion's Sa(T1) per building.

    bare: building -> its bare dataset; dampers: (building, kind) -> its damper dataset."""
    names = list(bare)
    kinds = [k for k in DAMPER_KINDS if all((b, k) in dampers for b in names)]
    damped = xr.concat([xr.concat([dampers[b, k] for k in kinds], dim="damper", join="outer", coords="minimal",
                                  data_vars="all", compat="override").assign_coords(damper=kinds) for b in names],
                       dim="building", coords="minimal", data_vars="all", compat="override")
    plain = xr.concat([bare[b][[*BARE_KEPT, "sa_record"]] for b in names], dim="building", coords="minimal",
                      compat="override")
    ds = damped.assign(
        drift_over_bare=(damped["drift_ratio"] / plain["drift_ratio"]).assign_attrs(
            long_name="peak inter-storey drift ratio over the bare building's, same ground motion and level",
            units="1"),
        **{f"bare_{name}": plain[name].assign_attrs(long_name="bare building: " + plain[name].attrs["long_name"])
           for name in BARE_KEPT},
        sa_record=plain["sa_record"]).assign_coords(building=names, damper=kinds)
    ds["building"].attrs = {"long_name": "building: storeys and fundamental period"}
    ds["damper"].attrs = {"long_name": "damper type"}
    first = bare[names[0]].attrs
    config = run_config(bare, dampers)
    ds.attrs = {"title": f"Incremental dynamic analysis on the FEMA P695 suites: {len(names)} buildings, bare and "
                         f"with {len(kinds)} dampers, {ds.sizes['motion']} ground motions, {ds.sizes['level']} levels",
                "buildings": ", ".join(names), "dampers": ", ".join(kinds),
                "storey_height_m": first["storey_height_m"], "zeta": first["zeta"],
                "initial_condition": first["initial_condition"],
                **({"config": config} if config is not None else {})}
    return ds


def run_config(bare: dict, dampers: dict) -> str | None:
    """The configuration the runs were made with (a damper run's; a bare run's is the same without the keys only
    the dampers' designs read, plan.DESIGN_KEYS), None where a run carries none; ValueError where they differ."""
    damped = {piece.attrs.get("config") for piece in dampers.values()}
    plain = {piece.attrs.get("config") for piece in bare.values()}
    if len(damped) > 1 or len(plain) > 1 or (damped and {_bare_view(c) for c in damped} != plain):
        raise ValueError("ida: the runs were made with different configurations")
    config = (damped or plain).pop()
    return None if config is None or None in plain else config


def _bare_view(config: str | None) -> str | None:
    """A damper run's configuration as a bare run of the same study keeps it (outputs.files.describe's JSON): its
    ida section, wherever the rule's params nest it, without the designs' keys."""
    def without_designs(params):
        if not isinstance(params, dict):
            return params
        return {key: ({k: v for k, v in value.items() if k not in DESIGN_KEYS} if key == "ida"
                      else without_designs(value)) for key, value in params.items()}
    return None if config is None else json.dumps(without_designs(json.loads(config)), sort_keys=True)


def bootstrap_median(values: np.ndarray, clusters: np.ndarray, samples: int, seed: int,
                     interval: float) -> tuple[float, float]:
    """The percentile interval of the median, resampling whole clusters (records) with replacement."""
    medians = cluster_draws(lambda idx: np.median(values[idx]), clusters, samples, seed)
    tail = 0.5 * (1.0 - interval)
    return float(np.quantile(medians, tail)), float(np.quantile(medians, 1.0 - tail))


def verdicts(ds: xr.Dataset, cfg: dict, level: float) -> pd.DataFrame:
    """Per building, damper, mass ratio and record group at one level: the median drift reduction over the bare
    building with its bootstrap interval over records, the shares of ground motions it helps and harms, and the
    damper's median stroke with the share of ground motions that took it to the stroke limit."""
    v = cfg["verdict"]
    ratio = ds["drift_over_bare"].sel(level=level)
    groups = ds["group"].values
    records = np.array([record_of(m) for m in ds["motion"].values])
    limit = math.inf if cfg["stroke_limit_m"] is None else cfg["stroke_limit_m"] * (1.0 - AT_LIMIT)
    rows = []
    for b in ds["building"].values:
        for kind in ds["damper"].values:
            for mr in ds["mass_ratio"].values:
                r = ratio.sel(building=b, damper=kind, mass_ratio=mr).values
                stroke = ds["stroke"].sel(building=b, damper=kind, mass_ratio=mr, level=level).values
                for group in GROUPS:
                    pick = groups == group
                    if not pick.any():
                        continue
                    lo, hi = bootstrap_median(1.0 - r[pick], records[pick], v["bootstrap"], v["seed"], v["interval"])
                    rows.append({"building": str(b), "damper": str(kind), "mass_ratio": float(mr), "group": group,
                                 "sa_g": level, "motions": int(pick.sum()),
                                 "median_reduction": float(np.median(1.0 - r[pick])),
                                 "reduction_low": lo, "reduction_high": hi,
                                 "share_lowered": float(np.mean(r[pick] <= 1.0 - v["improve"])),
                                 "share_raised": float(np.mean(r[pick] > 1.0 + v["worsen"])),
                                 "median_stroke_m": float(np.median(stroke[pick])),
                                 "share_at_stroke_limit": float(np.mean(stroke[pick] >= limit))})
    return pd.DataFrame(rows)


def lognormal_fit(levels: np.ndarray, exceed: np.ndarray, total: np.ndarray) -> tuple[float, float]:
    """Median theta and dispersion beta of P(exceed | Sa) = Phi(ln(Sa / theta) / beta), by maximum likelihood on
    the binomial counts at each level (Baker 2015).  NaN when no level is exceeded or every level is."""
    if exceed.sum() == 0 or exceed.sum() == total.sum():
        return math.nan, math.nan

    def negative_log_likelihood(p):
        prob = np.clip(stats.norm.cdf((np.log(levels) - p[0]) / math.exp(p[1])), 1e-12, 1.0 - 1e-12)
        return -float(np.sum(exceed * np.log(prob) + (total - exceed) * np.log(1.0 - prob)))

    start = [float(np.log(levels[np.argmin(np.abs(exceed / total - 0.5))])), math.log(0.4)]
    fit = optimize.minimize(negative_log_likelihood, start, method="Nelder-Mead",
                            options={"xatol": 1e-8, "fatol": 1e-10, "maxiter": 4000})
    return float(math.exp(fit.x[0])), float(math.exp(fit.x[1]))


def _cases(ds: xr.Dataset):
    """(damper label, mass ratio, drift ratio over (building, motion, level)) of the bare building and each damper."""
    yield "bare", math.nan, ds["bare_drift_ratio"]
    for kind in ds["damper"].values:
        for mr in ds["mass_ratio"].values:
            yield str(kind), float(mr), ds["drift_ratio"].sel(damper=kind, mass_ratio=mr)


def fragility(ds: xr.Dataset, limits: list[float]) -> pd.DataFrame:
    """Per building, case and drift limit: the share of ground motions over the limit at each level, and the
    lognormal fit of those shares."""
    levels = ds["level"].values
    rows = []
    for kind, mr, drift in _cases(ds):
        for b in ds["building"].values:
            d = drift.sel(building=b).values  # (motion, level)
            for limit in limits:
                over = (d > limit).sum(axis=0).astype(float)
                total = np.full(len(levels), float(d.shape[0]))
                theta, beta = lognormal_fit(levels, over, total)
                row = {"building": str(b), "damper": kind, "mass_ratio": mr, "drift_limit": limit,
                       "theta_sa_g": theta, "beta": beta}
                row.update({f"p_at_{lv:g}g": p for lv, p in zip(levels, over / total)})
                rows.append(row)
    return pd.DataFrame(rows)
