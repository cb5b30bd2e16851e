"""Figures of the study, drawn from the sweep datasets only (no simulation here)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from impact.model.kinds import CID, PID, TMD, damper_kinds, kind_of  # noqa: E402
from impact.model.params import curve_id  # noqa: E402
from impact.outputs.files import atomic_path  # noqa: E402
from impact.outputs.labels import TOO_SLOW  # noqa: E402
from impact.outputs.labels import label as label_of  # noqa: E402

IPC_MARKERS = {0: ("o", "none", "<1 IPC"), 1: ("^", "none", "1 IPC"), 2: ("o", "full", "2 IPC"), 3: ("s", "none", ">2 IPC")}
START_STYLE = {"centre": "-", "left": ":", "right": "--"}


def curve_label(spec: dict) -> str:
    parts = [spec["damper"].upper(), f"μ={spec['mu']:g}", f"e={spec['e']:g}"]
    if kind_of(spec["damper"]).spring:
        parts.append(f"r'={spec['rp']:g}")
    if spec.get("nu", 0.0):
        parts.append(f"ν={spec['nu']:g}")
    return " ".join(parts)


#: two curves of a panel closer than this everywhere (in X_m) are drawn on one another: the legend says so
SAME_CURVE = 5e-3


def _draw_curve(ax, ds, spec, color, drawn: list):
    """One curve per start; a curve that lies on one drawn before it in the panel joins that one's legend entry
    instead of having its own (a reader would look for it in vain)."""
    g = ds["gap_ratio"].values
    for start in ds["start"].values:
        xm = ds["X_m"].sel(start=start).values
        ipc = ds["ipc_class_at_max"].sel(start=start).values
        style = START_STYLE.get(str(start), "-")
        name = f"{curve_label(spec)}, start {start}"
        under = next((line for line, ys in drawn if ys.shape == xm.shape and np.all(np.abs(ys - xm) <= SAME_CURVE)),
                     None)
        if under is not None:
            under.set_label(f"{under.get_label()}; {name} (on it)")
        line, = ax.plot(g, xm, style, color=color, lw=1.0, label="_nolegend_" if under is not None else name)
        if under is None:
            drawn.append((line, xm))
        if "X_m_refined" in ds:  # the true peak between grid frequencies, as a thin line
            ax.plot(g, ds["X_m_refined"].sel(start=start).values, style, color=color, lw=0.4)
        for cls, (marker, fill, _) in IPC_MARKERS.items():
            sel = ipc == cls
            if np.any(sel):
                ax.plot(g[sel], xm[sel], marker, ms=4, color=color,
                        markerfacecolor=color if fill == "full" else "white", linestyle="none")


def _legend_for_markers(ax):
    ax.plot([], [], "-", color="0.3", lw=0.4, label="thin: peak refined between grid frequencies")
    for cls, (marker, fill, label) in IPC_MARKERS.items():
        ax.plot([], [], marker, color="0.3", markerfacecolor="0.3" if fill == "full" else "white",
                linestyle="none", label=label)


def plot_figure(fig_cfg: dict, datasets: dict, tmd: dict | None, outputs) -> None:
    """Draw a figure: one panel per configured panel, X_m against g.

    datasets: curve id -> xarray.Dataset; tmd: the optimum TMD (dict with X_m)
    or None; outputs: paths (.png, .pdf), each written atomically.
    """
    panels = fig_cfg["panels"]
    ncols = 2 if len(panels) > 1 else 1
    nrows = int(np.ceil(len(panels) / ncols))
    # each panel's legend sits below it, off the curves (the low X_m region is what a reader looks for)
    fig, axes = plt.subplots(nrows, ncols, figsize=(6.2 * ncols, 5.6 * nrows), squeeze=False, layout="constrained")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, panel in zip(axes.flat, panels):
        drawn = []
        for k, spec in enumerate(panel["curves"]):
            _draw_curve(ax, datasets[curve_id(spec)], spec, colors[k % len(colors)], drawn)
        if tmd is not None:
            ax.axhline(tmd["X_m"], color="k", ls="--", lw=1.0,
                       label=f"optimum TMD (f={tmd['f']:.3f}, βt={tmd['beta_t']:.3f})")
        _legend_for_markers(ax)
        if len(panels) > 1:  # one panel: the figure's title is its title
            ax.set_title(panel.get("title", ""))
        ax.set_xlabel("gap ratio g = d / A_max")
        ax.set_ylabel("amplitude ratio X_m")
        ax.set_ylim(0.0, 1.1)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6.5, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, frameon=False)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    fig.suptitle(fig_cfg.get("title", ""), fontsize=10)
    save_all(fig, outputs)


def plot_design_equations(ds, outputs) -> None:
    """The design equations against simulation: the formula's X_m against X_m simulated at the formula's gap
    (left), and that against the least X_m over the gap ratios (right: the grid refined around its best); one
    marker per damper type, filled where the point was held out of the fit."""
    fig, (left, right) = plt.subplots(1, 2, figsize=(9.0, 4.0), constrained_layout=True)
    for (kind, marker), color in zip(zip(sorted(set(ds["kind"].values)), "os^"), ("C0", "C1", "C2")):
        for held, label, fill in ((1.0, "held out", color), (0.0, "fitted", "none")):
            rows = ds.where((ds["kind"] == kind) & (ds["held_out"] == held), drop=True)
            style = dict(marker=marker, facecolors=fill, edgecolors=color, label=f"{kind.upper()}, {label}")
            left.scatter(rows["X_m_at_formula_gap"], rows["X_m_formula"], **style)
            right.scatter(rows["X_m_best"], rows["X_m_at_formula_gap"], **style)
    for ax, (x, y) in zip((left, right), (("X_m simulated at the formula's gap", "X_m by the formula"),
                                          ("the least X_m over the gap ratios", "X_m simulated at the formula's gap"))):
        ax.plot([0, 1], [0, 1], color="0.5", lw=0.8, label="equal")
        ax.plot([0, 1], [0, 1.1], color="0.5", lw=0.8, ls=":", label="10 % above")
        ax.set(xlabel=x, ylabel=y, xlim=(0, 1), ylim=(0, 1.1))
        ax.legend(fontsize=7)
    fig.suptitle("Design equations against direct simulation", fontsize=10)
    save_all(fig, outputs)


def save_atomic(fig, path) -> None:
    path = Path(path)
    with atomic_path(path, suffix=path.suffix) as tmp:
        fig.savefig(tmp, dpi=130, metadata={"CreationDate": None} if path.suffix == ".pdf" else None)


def save_all(fig, outputs) -> None:
    """The figure to each of its files (PNG and PDF), then closed."""
    for out in outputs:
        save_atomic(fig, out)
    plt.close(fig)


CHART_COLORS = ["#f0f0f0", "#c8c8c8", "#f4a582", "#4393c3"]
CHART_LABELS = ["no 2-EIPC root", "roots, none admissible", "admissible, unstable", "admissible, stable"]


def plot_stability_chart(ds, outputs) -> None:
    """Masri's 2-EIPC existence and stability in the (r, d/(F0/K)) plane, one panel per e."""
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    n = ds.sizes["e"]
    fig, axes = plt.subplots(1, n, figsize=(4.6 * n, 4.2), squeeze=False, sharey=True)
    for ax, e in zip(axes.flat, ds["e"].values):
        cls = ds["class"].sel(e=e).values
        ax.pcolormesh(ds["r"].values, ds["d_over_xst"].values, cls, cmap=ListedColormap(CHART_COLORS),
                      vmin=-0.5, vmax=3.5, shading="nearest")
        ax.set_title(f"μ={ds.attrs['mu']:g}, e={e:g}, β={ds.attrs['beta']:g}")
        ax.set_xlabel("frequency ratio r")
    axes.flat[0].set_ylabel("total clearance d / (F0/K)")
    handles = [Patch(color=c, label=lab) for c, lab in zip(CHART_COLORS, CHART_LABELS)]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, 0.08, 1, 1))
    save_all(fig, outputs)


def plot_branches(ds, outputs) -> None:
    """Closed-form 2-EIPC branches (stable solid, unstable dashed) and runs from rest."""
    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    r = ds["r"].values
    for name, color in zip(ds["root"].values, ("C0", "C3")):
        amp = ds["closed_form"].sel(root=name).values
        stable = ds["stable"].sel(root=name).values.astype(bool)
        ax.plot(r, np.where(stable, amp, np.nan), "-", color=color, lw=1.6, label=f"closed form, {name} root, stable")
        ax.plot(r, np.where(~stable, amp, np.nan), "--", color=color, lw=1.0, label=f"closed form, {name} root, unstable")
    for start, marker in zip(ds["start"].values, ("o", "x", "+")):
        ax.plot(r, ds["simulated"].sel(start=start).values, marker, ms=4, color="k", mfc="none",
                linestyle="none", label=f"simulation from rest, start {start}")
    ax.set_xlabel("frequency ratio r")
    ax.set_ylabel("√2·RMS amplitude / (F0/K)")
    ax.set_title(f"CID μ={ds.attrs['mu']:g}, e={ds.attrs['e']:g}, g={ds.attrs['gap_ratio']:g}: "
                 "closed form (Masri) and simulation")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save_all(fig, outputs)


MODE_STYLE = {"from_rest": "-", "continuation_up": "--", "continuation_down": "-."}
START_COLORS = {"centre": "C0", "left": "C1", "right": "C2"}
START_MARKERS = {"centre": "o", "left": "s", "right": "^"}


def plot_coexistence(spec: dict, from_rest, continuation: dict, ensemble, outputs) -> None:
    """X_m against g: from rest, both continuation directions, and the ensemble's envelope."""
    fig, ax = plt.subplots(figsize=(9.4, 4.8), layout="constrained")
    g = ensemble["gap_ratio"].values if ensemble is not None else from_rest["gap_ratio"].values
    if ensemble is not None:
        ax.fill_between(g, ensemble["X_m_min"].values, ensemble["X_m_max"].values, color="0.85",
                        label=f"ensemble envelope ({ensemble.sizes['member']} starts)")
        ax.plot(g, ensemble["X_m_median"].values, color="0.5", lw=1.0, label="ensemble median")
    datasets = {"from_rest": from_rest, **continuation}
    for mode, ds in datasets.items():
        for start in ds["start"].values:
            ax.plot(ds["gap_ratio"].values, ds["X_m"].sel(start=start).values, MODE_STYLE.get(mode, "-"),
                    color=START_COLORS.get(str(start), "k"), lw=1.2, marker=".", ms=3,
                    label=f"{mode.replace('_', ' ')}, start {start}")
    ax.set_xlabel("gap ratio g = d / A_max")
    ax.set_ylabel("amplitude ratio X_m")
    ax.set_ylim(0.0, 1.1)
    ax.grid(alpha=0.3)
    ax.set_title(f"{curve_label(spec)}: sweep protocol and initial condition")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    save_all(fig, outputs)


def plot_hysteresis(spec: dict, continuation: dict, from_rest, branches, gap_ratio: float, xst_over_amax: float,
                    outputs) -> None:
    """Frequency response at one gap: up- and down-sweep branches and the closed-form 2-EIPC branch."""
    fig, ax = plt.subplots(figsize=(9.4, 4.8), layout="constrained")
    for mode, ds in continuation.items():
        for start in ds["start"].values:
            amp = ds["amplitude_ratio"].sel(start=start, gap_ratio=gap_ratio).values
            ax.plot(ds["freq_ratio"].values, amp, MODE_STYLE.get(mode, "-"), marker=".", ms=4, lw=1.0,
                    color=START_COLORS.get(str(start), "k"), label=f"{mode.replace('_', ' ')}, start {start}")
    for start in from_rest["start"].values:
        amp = from_rest["amplitude_ratio"].sel(start=start, gap_ratio=gap_ratio).values
        ax.plot(from_rest["freq_ratio"].values, amp, START_MARKERS.get(str(start), "o"), mfc="none", ms=5,
                color=START_COLORS.get(str(start), "0.4"), label=f"from rest, start {start}")
    if branches is not None:
        for name in ("upper", "lower"):
            sub = branches[branches["root"] == name]
            stable = sub["stable"].to_numpy()
            amp = sub["amplitude_over_xst"].to_numpy() * xst_over_amax
            ax.plot(sub["r"], np.where(stable, amp, np.nan), "k-", lw=2.0, alpha=0.6,
                    label="closed form 2 EIPC, stable" if name == "upper" else None)
            ax.plot(sub["r"], np.where(~stable, amp, np.nan), "k:", lw=1.0,
                    label="closed form 2 EIPC, unstable" if name == "upper" else None)
    ax.set_xlabel("frequency ratio r")
    ax.set_ylabel("√2·RMS amplitude / A_max")
    ax.set_title(f"{curve_label(spec)}, g = {gap_ratio:g}: hysteresis of the frequency response")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    save_all(fig, outputs)


def plot_work_precision(ds, footer: str, outputs, error: str = "amplitude_error") -> None:
    """Error against wall time, log-log, one panel per case, one line per integrator."""
    cases = list(ds["case"].values)
    ncols = 2
    nrows = int(np.ceil(len(cases) / ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(6.4 * ncols, 4.4 * nrows), squeeze=False)
    markers = dict(zip(ds["integrator"].values, "*osD^v<>ph"))
    floor = 1e-17  # exact agreement is drawn at the floor instead of vanishing on a log axis
    for ax, case in zip(axes.flat, cases):
        for integ in ds["integrator"].values:
            t = ds["wall_time"].sel(case=case, integrator=integ).values
            e = ds[error].sel(case=case, integrator=integ).values
            ok = np.isfinite(t) & np.isfinite(e)
            if not ok.any():
                continue
            style = dict(ms=10, color="k") if integ == "core" else dict(ms=5)
            label = "exact core (the reference, drawn at the floor)" if integ == "core" else label_of(integ)
            ax.loglog(t[ok], np.maximum(e[ok], floor), "-" + markers.get(integ, "o"), label=label, **style)
        horizon = float(ds["predictability_horizon"].sel(case=case))
        title = label_of(case) + (f"\n(inside its predictability horizon, t < {horizon:.0f})"
                                  if np.isfinite(horizon) else "")
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("wall time per run [s] (min of repeats)")
        ax.set_ylabel(f"{error.replace('_', ' ')} against the exact core")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(cases):]:
        ax.set_visible(False)
    fig.text(0.01, 0.005, footer, fontsize=6.5, va="bottom")
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    save_all(fig, outputs)


def plot_stability_map(table, outputs) -> None:
    """Heat map case x method: ok (finished within tolerance), finished outside it, or failed (annotated)."""

    cases = list(dict.fromkeys(table["case"]))
    methods = list(dict.fromkeys(table["method"]))
    grid = np.zeros((len(cases), len(methods)))
    fig, ax = plt.subplots(figsize=(1.2 * len(methods) + 3, 0.45 * len(cases) + 2))
    for _, row in table.iterrows():
        i, j = cases.index(row["case"]), methods.index(row["method"])
        failed = not str(row["status"]).startswith("ok") or not row["finite"]
        grid[i, j] = 2 if failed else (0 if row["ok"] else 1)
        pen = row.get("max_penetration", np.nan)
        if failed or not (np.isfinite(pen) and pen > 0):
            label = ("too slow" if TOO_SLOW in str(row["status"]) else "failed") if failed else (
                "ok" if row["ok"] else "amplitude off")
        else:
            label = f"pen {pen:.0e}"
        ax.text(j, i, label, ha="center", va="center", fontsize=6)
    from matplotlib.colors import ListedColormap

    ax.imshow(grid, cmap=ListedColormap(["#a6dba0", "#fdb863", "#e66101"]), vmin=0, vmax=2, aspect="auto")
    ax.set_xticks(range(len(methods)), [label_of(m) for m in methods], rotation=30, ha="right", fontsize=8)
    ax.set_yticks(range(len(cases)), [label_of(c) for c in cases], fontsize=8)
    ax.set_title("Extreme cases: green ok (penetration <= 1e-6 of the gap, amplitude within 1e-3 of the core's),\n"
                 "orange finished outside that, red failed or non-finite (largest penetration beyond a wall)",
                 fontsize=9)
    fig.tight_layout()
    save_all(fig, outputs)


ROBUSTNESS_PANELS = (
    ("scale", "force amplitude over the design's", "log"),
    ("drift", "drift of the structure's frequency (%)", "linear"),
    ("damping", "damper damping ratio", "log"),
    ("e", "coefficient of restitution e", "linear"),
)


def _few_ticks(ax, xscale: str, percent: bool = False) -> None:
    """At most five plain tick labels on the x axis (no 10^x, no crowding)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

    if xscale == "log":
        ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0), numticks=5))
        ax.xaxis.set_minor_formatter(NullFormatter())
    else:
        ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{100 * v:g}" if percent else f"{v:g}"))


def plot_robustness(designs: dict, outputs) -> None:
    """X_m against each variation (Table 1's rows 9, 6, 7 and 10), one line per design, design points marked.

    designs: design name -> its robustness dataset.
    """
    fig, axes = plt.subplots(2, 3, figsize=(15.0, 8.0), layout="constrained")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    design_at = {"scale": lambda ds: 1.0, "drift": lambda ds: 0.0, "e": lambda ds: None, "damping": lambda ds: None}
    for ax, (name, label, xscale) in zip(axes.flat, ROBUSTNESS_PANELS):
        for k, (design, ds) in enumerate(designs.items()):
            if f"X_m_vs_{name}" not in ds:
                continue
            color = colors[k % len(colors)]
            ax.plot(ds[name].values, ds[f"X_m_vs_{name}"].values, "o-", ms=3, lw=1.0, color=color,
                    label=label_of(design))
            at = design_at[name](ds)
            if at is not None:
                ax.plot([at], [float(ds["X_m_design"])], "*", ms=9, color=color)
        ax.set_xscale(xscale)
        _few_ticks(ax, xscale, percent=name == "drift")
        ax.set_xlabel(label)
        ax.set_ylabel("amplitude ratio X_m")
        ax.grid(alpha=0.3)
    _plot_units(axes.flat[len(ROBUSTNESS_PANELS)], designs, colors)
    # one legend for every panel, in the sixth place
    legend_ax = axes.flat[-1]
    legend_ax.axis("off")
    handles = [plt.Line2D([], [], color=colors[k % len(colors)], marker="o", ms=4, label=label_of(design))
               for k, design in enumerate(designs)]
    handles.append(plt.Line2D([], [], color="0.3", marker="*", ms=9, ls="none", label="design point"))
    legend_ax.legend(handles=handles, loc="center", fontsize=9, frameon=False, title="design")
    fig.suptitle("Table 1 in numbers: X_m as what the designer does not control changes (stars: design points)",
                 fontsize=10)
    save_all(fig, outputs)


def _plot_units(ax, designs: dict, colors) -> None:
    """X_m against the number of units: all at the design's start (solid), staggered (dashed), the
    ensemble's range (band)."""
    for k, (design, ds) in enumerate(designs.items()):
        if "X_m_units_symmetric" not in ds:
            continue
        color, n = colors[k % len(colors)], ds["units"].values
        ens = ds["X_m_units_ensemble"].values
        ax.plot(n, ds["X_m_units_symmetric"].values, "o-", ms=3, lw=1.0, color=color, label=label_of(design))
        ax.plot(n, ds["X_m_units_staggered"].values, "s--", ms=3, lw=1.0, color=color)
        ax.fill_between(n, ens.min(axis=1), ens.max(axis=1), color=color, alpha=0.15, lw=0)
    ax.set_xlabel("number of units (same total mass and gap)")
    ax.set_ylabel("amplitude ratio X_m")
    ax.set_title("solid: units start together; dashed: staggered; band: random starts", fontsize=8)
    ax.xaxis.set_major_locator(plt.MaxNLocator(integer=True))
    ax.grid(alpha=0.3)


XM_LEVELS = [0.0, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5, 0.7, 1.0, 1.5]


def _cell_edges(centres, log: bool = False) -> np.ndarray:
    """Edges of cells centred on the grid's values (in log space for a log axis; a single value gets a cell of
    10 % of itself)."""
    c = np.log(np.asarray(centres, dtype=float)) if log else np.asarray(centres, dtype=float)
    if len(c) == 1:
        half = 0.05 * (abs(c[0]) or 1.0)
        edges = np.array([c[0] - half, c[0] + half])
    else:
        mid = 0.5 * (c[1:] + c[:-1])
        edges = np.concatenate(([2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]))
    return np.exp(edges) if log else edges


def _geometric(values) -> bool:
    """A grid of positive values spread over more than a factor of 3: drawn on a log axis."""
    v = np.asarray(values, dtype=float)
    return len(v) > 1 and bool(np.all(v > 0)) and v.max() / v.min() > 3.0


def _chart_panel(ax, x, y, values, norm, title: str, xlabel: str, ylabel: str):
    """X_m on a chart's grid as coloured cells (no interpolation between runs), with labelled contour lines;
    a geometric grid on a log axis, ticks at the grid's own values, the axes ending with the cells."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

    logx, logy = _geometric(x), _geometric(y)
    xe, ye = _cell_edges(x, logx), _cell_edges(y, logy)
    mesh = ax.pcolormesh(xe, ye, values, shading="flat", cmap="viridis_r", norm=norm)
    if min(values.shape) >= 2:
        lines = ax.contour(x, y, values, levels=XM_LEVELS[1:], colors="k", linewidths=0.6)
        ax.clabel(lines, fontsize=8, fmt="%g")
    for axis, log, grid, edges in ((ax.xaxis, logx, x, xe), (ax.yaxis, logy, y, ye)):
        if log:
            (ax.set_xscale if axis is ax.xaxis else ax.set_yscale)("log")
            shown = grid if len(grid) <= 6 else [v for v in (0.2, 0.5, 1.0, 2.0, 5.0, 10.0) if edges[0] <= v <= edges[-1]]
            axis.set_major_locator(FixedLocator(shown))
            axis.set_minor_locator(NullLocator())
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.set_xlim(xe[0], xe[-1])
    ax.set_ylim(ye[0], ye[-1])
    ax.set_title(title, fontsize=10)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    return mesh


def plot_design_charts(charts: dict, outputs) -> None:
    """The design charts: per e, the CID's X_m over (mu, g) beside the PID's at its best g over (mu, r'); below
    them X_m at each damper's best design and the best gap ratio against mu.  Two charts a row, so that a page's
    width shows their contour labels."""
    from matplotlib.colors import BoundaryNorm

    cid, pid, tmd = charts[CID], charts[PID], charts[TMD]
    es = cid["e"].values
    norm = BoundaryNorm(XM_LEVELS, plt.get_cmap("viridis_r").N, extend="max")
    fig, axes = plt.subplots(len(es) + 1, 2, figsize=(11.0, 3.7 * (len(es) + 1)), squeeze=False,
                             layout="constrained")
    for j, e in enumerate(es):
        c = cid.sel(e=e)
        mesh = _chart_panel(axes[j, 0], c["mu"].values, c["gap_ratio"].values, c["X_m"].values.T, norm,
                            f"CID, e = {e:g}: X_m (worst start; stars: best g)", "mass ratio μ", "gap ratio g")
        axes[j, 0].plot(c["mu"].values, c["gap_ratio_best"].values, "w*-", ms=7, lw=0.8)
        p = pid.sel(e=e)
        _chart_panel(axes[j, 1], p["mu"].values, p["rp"].values, p["X_m_best"].values.T, norm,
                     f"PID, e = {e:g}: X_m at its best g", "mass ratio μ", "tuning r'")
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    best, gaps = axes[-1, 0], axes[-1, 1]
    for j, e in enumerate(es):
        color = colors[j % len(colors)]
        best.plot(cid["mu"].values, cid["X_m_best"].sel(e=e).values, "o-", color=color, ms=3, label=f"CID e={e:g}")
        p = pid.sel(e=e)
        k = p["X_m_best"].argmin("rp")
        best.plot(p["mu"].values, p["X_m_best"].min("rp").values, "s--", color=color, ms=3,
                  label=f"PID e={e:g} (best r')")
        gaps.plot(cid["mu"].values, cid["gap_ratio_best"].sel(e=e).values, "o-", color=color, ms=3,
                  label=f"CID e={e:g}")
        gaps.plot(p["mu"].values, p["gap_ratio_best"].isel(rp=k).values, "s--", color=color, ms=3,
                  label=f"PID e={e:g}")
    best.plot(tmd["mu"].values, tmd["X_m"].values, "k-", lw=1.5, label="TMD (equal-peak optimum)")
    best.set(xlabel="mass ratio μ", ylabel="X_m at the best design", title="each damper at its best")
    gaps.set(xlabel="mass ratio μ", ylabel="best gap ratio g", title="the gap of each best design")
    for ax in (best, gaps):
        if _geometric(cid["mu"].values):
            ax.set_xscale("log")
            ax.xaxis.set_major_locator(plt.FixedLocator(cid["mu"].values))
            ax.xaxis.set_minor_locator(plt.NullLocator())
            ax.xaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, ncol=2)
    fig.colorbar(mesh, ax=axes[:-1, :], shrink=0.6, label="X_m = x_max / A_max")
    fig.suptitle(textwrap.fill(f"Design charts for {cid.attrs['design_point']}", 120), fontsize=10)
    save_all(fig, outputs)


LOAD_COLUMNS = (("records", None, "the four records (mean)"), ("kanai_tajimi", "firm", "Kanai-Tajimi, firm (mean)"),
                ("kanai_tajimi", "soft", "Kanai-Tajimi, soft (mean)"))
DAMPER_COLORS = {kind: f"C{i}" for i, kind in enumerate(damper_kinds())}  # each kind its colour, in the registry's order


def plot_loads_reduction(datasets: dict, outputs) -> None:
    """Peak roof displacement over the bare building's against PGA: one row per building, one column per
    load group (records, Kanai-Tajimi per soil), one line per damper and mass ratio."""
    columns = [(f, soil, title) for f, soil, title in LOAD_COLUMNS
               if f in datasets and (soil is None or soil in datasets[f]["soil"].values)]
    names = list(datasets[columns[0][0]]["building"].values)
    # small multiples on one scale: a building a row (named at its left), a load group a column (named on top)
    fig, axes = plt.subplots(len(names), len(columns), figsize=(3.6 * len(columns) + 1.2, 1.35 * len(names) + 1.2),
                             squeeze=False, sharex=True, sharey=True, layout="constrained")
    for j, (family, soil, title) in enumerate(columns):
        ds = datasets[family] if soil is None else datasets[family].sel(soil=soil)
        ratio = ds["peak_roof_ratio"].mean("record" if family == "records" else "seed")
        for i, building in enumerate(names):
            ax = axes[i, j]
            for damper in ratio["damper"].values:
                for k, mr in enumerate(ratio["mass_ratio"].values):
                    ax.plot(ratio["intensity"].values, ratio.sel(building=building, damper=damper, mass_ratio=mr),
                            "o-" if k == len(ratio["mass_ratio"]) - 1 else "s--", ms=3, lw=1.0,
                            color=DAMPER_COLORS[str(damper)], label=f"{str(damper).upper()} {mr:g}")
            ax.axhline(1.0, color="k", lw=0.6)
            ax.grid(alpha=0.3)
            ax.tick_params(labelsize=7)
            if i == 0:
                ax.set_title(title, fontsize=9)
            if j == 0:
                ax.set_ylabel(label_of(building).replace(", ", "\n"), fontsize=8)
            if i == len(names) - 1:
                ax.set_xlabel("PGA (g)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), fontsize=8, frameon=False)
    fig.suptitle("Peak roof displacement with each damper over the bare building's (below 1: it helps; "
                 "solid: the larger mass ratio)", fontsize=10)
    fig.supylabel("peak roof displacement / the bare building's (each row: one building)", fontsize=9)
    save_all(fig, outputs)


def plot_time_history(ds, outputs) -> None:
    """A run in time (outputs.datasets.time_history_dataset): the roof with (and without) the damper, and the
    damper's stroke between its walls, impacts marked.  Metres are drawn in cm; model units as they are."""
    t = ds["t"].values
    unit = ds["stroke"].attrs["units"]
    scale, label = (100.0, "cm") if unit == "m" else (1.0, "model units")
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(11.0, 6.0), sharex=True, layout="constrained")
    if "roof_bare" in ds:
        top.plot(t, ds["roof_bare"].values * scale, color="0.5", lw=0.8, label="bare")
    top.plot(t, ds["roof_damped"].values * scale, color="C0", lw=0.8, label=f"with the {ds.attrs['damper'].upper()}")
    top.set_ylabel(f"roof displacement ({label})")
    top.legend(fontsize=8)
    half = float(ds["half_gap"]) * scale
    stroke = ds["stroke"].values * scale
    bottom.plot(t, stroke, color="C1", lw=0.8, label="damper mass relative to its floor")
    if np.isfinite(half):  # a TMD has no walls and no impacts
        for wall in (-half, half):
            bottom.axhline(wall, color="k", lw=0.6, ls="--")
        impacts = ds["impact_time"].values
        bottom.plot(impacts, np.interp(impacts, t, stroke), "k|", ms=8, label=f"impacts ({len(impacts)})")
    bottom.set_ylabel(f"stroke ({label})")
    bottom.set_xlabel("time (s)" if unit == "m" else "time (model units: radians of the structure)")
    bottom.legend(fontsize=8)
    fig.suptitle(ds.attrs["title"], fontsize=9)
    save_all(fig, outputs)
