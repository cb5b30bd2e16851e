"""The collapse assessment's figure: one archetype's pushover, IDA curves to collapse and collapse fragility curves
(drawn from the stage's run datasets only; no simulation here)."""

from __future__ import annotations

import numpy as np

from impact.model.kinds import damper_kinds
from impact.outputs.ida_figures import CASE_COLORS
from impact.outputs.labels import label
from impact.outputs.plotting import plt, save_all

#: dampers that change the collapse little draw over one another: each its own dash, the bare building solid
DASHES = ("--", "-.", ":", (0, (5, 1, 1, 1, 1, 1)), (0, (1, 3)))
LINESTYLES = {"bare": "-", **{kind: DASHES[i % len(DASHES)] for i, kind in enumerate(damper_kinds())}}


def _pushover_panel(ax, bare) -> None:
    a = bare.attrs
    ax.plot(bare["pushover_roof_drift"].values, bare["pushover_base_shear"].values, "k-", lw=1.4)
    ax.axvline(a["yield_roof_drift_m"], color="0.5", ls="--", lw=0.8,
               label=f"effective yield, {a['yield_roof_drift_m']:.3f} m")
    ax.axvline(a["ultimate_roof_drift_m"], color="r", ls=":", lw=1.0,
               label=f"ultimate ({a['ultimate_by']}), {a['ultimate_roof_drift_m']:.3f} m")
    ax.set(title=f"pushover: μ_T = {a['mu_T']:.2f}", xlabel="roof drift (m)",
           ylabel="base shear / weight")
    ax.legend(fontsize=6)


def _ida_panel(ax, runs, title: str) -> None:
    """Each motion's runs sorted by level: drift ratio against Sa(T1), its collapse as a cross."""
    sa, drift, collapsed = runs["run_sa"].values, runs["run_drift_ratio"].values, runs["run_collapsed"].values
    hit = runs["collapse_sa"].values
    limit = 100.0 * runs.attrs["drift_limit"]
    for i in range(sa.shape[0]):
        stood = (collapsed[i] == 0) & (sa[i] < np.nan_to_num(hit[i], nan=np.inf))
        ax.plot(100.0 * drift[i][stood], sa[i][stood], "-", color="0.6", lw=0.5)
        if np.isfinite(hit[i]) and stood.any():  # from the last level that stood to the collapse
            ax.plot([100.0 * drift[i][stood][-1], limit], [sa[i][stood][-1], hit[i]], ":", color="0.6", lw=0.5)
    ax.plot(np.full(np.isfinite(hit).sum(), limit), hit[np.isfinite(hit)], "rx", ms=3, label="collapse")
    ax.set(title=title, xlabel="peak inter-storey drift ratio (%)", xlim=(0.0, 1.05 * limit))


def _fragility_panel(ax, cases, s_mt: float) -> None:
    """The share of ground motions collapsed at or below each Sa(T1), per case (steps), with the MCE demand."""
    top = max((float(np.nanmax(c["collapse_sa"].values)) for _, c in cases if np.isfinite(c["collapse_sa"]).any()),
              default=s_mt)
    grid = np.linspace(0.0, 1.1 * top, 400)
    for name, c in cases:
        hit = np.nan_to_num(c["collapse_sa"].values, nan=np.inf)
        share = (hit[:, None] <= grid[None, :]).mean(axis=0)
        kind = name.split(",")[0].lower()
        ax.step(grid, share, where="post", color=CASE_COLORS.get(kind, "k"), lw=1.2, label=name,
                ls=LINESTYLES.get(kind, "-"))
    ax.axvline(s_mt, color="k", ls=":", lw=0.8, label=f"MCE demand S_MT {s_mt:.2f} g")
    ax.set(title="collapse fragility", xlabel="Sa(T1) (g)",
           ylabel="probability of collapse", ylim=(-0.03, 1.03))
    ax.legend(fontsize=6, loc="lower right")


def plot_collapse_archetype(bare, dampers: dict, building: str, outputs) -> None:
    """Top row: the pushover and the bare archetype's IDA curves to collapse; then each damper's (the larger mass
    ratio); last: the collapse fragility of every case."""
    mass_ratio = max((float(d["mass_ratio"].values[-1]) for d in dampers.values()), default=float("nan"))
    cases = [("bare", bare)] + [(f"{kind.upper()}, {100 * mass_ratio:g} % mass", d.sel(mass_ratio=mass_ratio))
                                for kind, d in dampers.items()]
    panels = 2 + len(dampers) + 1
    columns = 3
    rows = -(-panels // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(3.4 * columns, 3.2 * rows), layout="constrained", squeeze=False)
    flat = axes.ravel()
    _pushover_panel(flat[0], bare)
    for ax, (name, runs) in zip(flat[1:], cases):
        _ida_panel(ax, runs, name)
        ax.set_ylabel("Sa(T1) (g)")
    flat[1].legend(fontsize=6)
    _fragility_panel(flat[1 + len(cases)], cases, float(bare.attrs["S_MT_g"]))
    for ax in flat[2 + len(cases):]:
        ax.set_axis_off()
    fig.suptitle(f"Collapse of the yielding archetype {label(building)}: {bare.sizes['motion']} FEMA P695 ground "
                 f"motions traced to a {100 * bare.attrs['drift_limit']:g} % storey drift", fontsize=10)
    save_all(fig, outputs)
