"""The incremental dynamic analysis's figure: one building's IDA curves, drift over the bare building's and
fragility curves (drawn from the collected dataset and the fits only; no simulation here)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from impact.model.suites import GROUPS
from impact.outputs.labels import label
from impact.outputs.plotting import DAMPER_COLORS, plt, save_all

CASE_COLORS = {"bare": "k", **DAMPER_COLORS}
GROUP_COLORS = dict(zip(GROUPS, ("#1b9e77", "#d95f02", "#7570b3")))
FRACTILES = (0.16, 0.5, 0.84)


def _drift_panel(ax, drift, levels, title: str) -> None:
    """Every ground motion's IDA curve (thin), the median and the 16/84 % fractiles of drift at each level."""
    for curve in drift:
        ax.plot(100.0 * curve, levels, color="0.75", lw=0.4)
    q = np.quantile(drift, FRACTILES, axis=0)
    ax.plot(100.0 * q[1], levels, "k-", lw=1.6, label="median")
    ax.plot(100.0 * q[0], levels, "k--", lw=1.0, label="16 / 84 %")
    ax.plot(100.0 * q[2], levels, "k--", lw=1.0)
    ax.set_xlim(0.0, 100.0 * float(np.quantile(drift[:, -1], 0.95)) * 1.1)
    ax.set(title=title, xlabel="peak inter-storey drift ratio (%)")


def _ratio_panel(ax, ratio, groups, levels, title: str) -> None:
    """The drift ratio over the bare building's per record group: median and 16-84 % band against Sa(T1)."""
    for group in GROUPS:
        pick = groups == group
        if not pick.any():
            continue
        q = np.quantile(ratio[pick], FRACTILES, axis=0)
        ax.fill_between(levels, q[0], q[2], color=GROUP_COLORS[group], alpha=0.15, lw=0)
        ax.plot(levels, q[1], "o-", ms=3, color=GROUP_COLORS[group], label=group)
    ax.axhline(1.0, color="k", lw=0.6)
    ax.set(title=title, xlabel="Sa(T1) (g)")


def _fit(fits: pd.DataFrame, building: str, kind: str, mass_ratio: float, limit: float) -> tuple[float, float]:
    """The lognormal fit's (theta, beta) of one case (the bare building's has no mass ratio)."""
    same_mass = fits.mass_ratio.isna() if kind == "bare" else fits.mass_ratio == mass_ratio
    row = fits[(fits.building == building) & (fits.damper == kind) & (fits.drift_limit == limit) & same_mass]
    return float(row.theta_sa_g.iloc[0]), float(row.beta.iloc[0])


def _fragility_panel(ax, ds, fits, building: str, mass_ratio: float, limit: float) -> None:
    """Per case, the share of ground motions over the drift limit at each level (dots) and its lognormal fit."""
    levels = ds["level"].values
    grid = np.linspace(levels[0], levels[-1], 200)
    cases = [("bare", ds["bare_drift_ratio"].values)]
    cases += [(str(k), ds["drift_ratio"].sel(damper=k, mass_ratio=mass_ratio).values)
              for k in ds["damper"].values]
    for kind, drift in cases:
        ax.plot(levels, np.mean(drift > limit, axis=0), "o", ms=3, color=CASE_COLORS[kind])
        theta, beta = _fit(fits, building, kind, mass_ratio, limit)
        if np.isfinite(theta):
            ax.plot(grid, stats.norm.cdf(np.log(grid / theta) / beta), "-", lw=1.0, color=CASE_COLORS[kind],
                    label=f"{kind.upper() if kind != 'bare' else 'bare'}: θ {theta:.2f} g, β {beta:.2f}")
    ax.set(title=f"P(drift ratio > {100 * limit:g} %)", xlabel="Sa(T1) (g)", ylim=(-0.03, 1.03))
    ax.legend(fontsize=6, loc="lower right")


def plot_ida_building(ds, fits: pd.DataFrame, building: str, cfg: dict, outputs) -> None:
    """Row 1: IDA curves of the bare building and each damper (the larger mass ratio); row 2: each damper's drift
    over the bare building's per record group; row 3: the probability of exceeding each drift limit."""
    ds = ds.sel(building=building)
    mass_ratio = float(ds["mass_ratio"].values[-1])
    levels, groups, kinds = ds["level"].values, ds["group"].values, [str(k) for k in ds["damper"].values]
    limits = list(cfg["drift_limits"])
    columns = max(1 + len(kinds), len(limits))
    fig, axes = plt.subplots(3, columns, figsize=(3.2 * columns, 9.6), layout="constrained", squeeze=False)
    _drift_panel(axes[0, 0], ds["bare_drift_ratio"].values, levels, "bare")
    for j, kind in enumerate(kinds, start=1):
        sel = ds.sel(damper=kind, mass_ratio=mass_ratio)
        _drift_panel(axes[0, j], sel["drift_ratio"].values, levels, f"{kind.upper()}, {100 * mass_ratio:g} % mass")
        _ratio_panel(axes[1, j - 1], sel["drift_over_bare"].values, groups, levels,
                     f"{kind.upper()} drift over bare")
    axes[0, 0].set_ylabel("Sa(T1) (g)")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].set_ylabel("drift ratio / bare (below 1: it helps)")
    axes[1, 0].legend(fontsize=7)
    for j, limit in enumerate(limits):
        _fragility_panel(axes[2, j], ds, fits, building, mass_ratio, limit)
    axes[2, 0].set_ylabel("probability of exceedance")
    for ax in axes[1, len(kinds):].tolist() + axes[2, len(limits):].tolist():
        ax.set_axis_off()
    fig.suptitle(f"Incremental dynamic analysis, {label(building)}: {len(ds['motion'])} FEMA P695 ground motions "
                 f"(thin: one each; median and 16/84 % fractiles)", fontsize=10)
    save_all(fig, outputs)
