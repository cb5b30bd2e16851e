"""Figures of the study, drawn from the sweep datasets only (no simulation here)."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .pipeline import publish as _publish  # noqa: E402
from .study import curve_id  # noqa: E402

IPC_MARKERS = {0: ("o", "none", "<1 IPC"), 1: ("^", "none", "1 IPC"), 2: ("o", "full", "2 IPC"), 3: ("s", "none", ">2 IPC")}
START_STYLE = {"centre": "-", "left": ":", "right": "--"}


def curve_label(spec: dict) -> str:
    parts = [spec["damper"].upper(), f"μ={spec['mu']:g}", f"e={spec['e']:g}"]
    if spec["damper"] == "pid":
        parts.append(f"r'={spec['rp']:g}")
    if spec.get("nu", 0.0):
        parts.append(f"ν={spec['nu']:g}")
    return " ".join(parts)


def _draw_curve(ax, ds, spec, color):
    g = ds["gap_ratio"].values
    for start in ds["start"].values:
        xm = ds["X_m"].sel(start=start).values
        ipc = ds["ipc_class_at_max"].sel(start=start).values
        style = START_STYLE.get(str(start), "-")
        ax.plot(g, xm, style, color=color, lw=1.0, label=f"{curve_label(spec)}, start {start}")
        for cls, (marker, fill, _) in IPC_MARKERS.items():
            sel = ipc == cls
            if np.any(sel):
                ax.plot(g[sel], xm[sel], marker, ms=4, color=color,
                        markerfacecolor=color if fill == "full" else "white", linestyle="none")


def _legend_for_markers(ax):
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
    fig, axes = plt.subplots(nrows, ncols, figsize=(6.2 * ncols, 4.4 * nrows), squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, panel in zip(axes.flat, panels):
        for k, spec in enumerate(panel["curves"]):
            _draw_curve(ax, datasets[curve_id(spec)], spec, colors[k % len(colors)])
        if tmd is not None:
            ax.axhline(tmd["X_m"], color="k", ls="--", lw=1.0,
                       label=f"optimum TMD (f={tmd['f']:.3f}, βt={tmd['beta_t']:.3f})")
        _legend_for_markers(ax)
        ax.set_title(panel.get("title", ""))
        ax.set_xlabel("gap ratio g = d / A_max")
        ax.set_ylabel("amplitude ratio X_m")
        ax.set_ylim(0.0, 1.1)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=6.5, loc="best", ncol=2)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    fig.suptitle(fig_cfg.get("title", ""), fontsize=10)
    fig.tight_layout()
    for out in outputs:
        save_atomic(fig, out)
    plt.close(fig)


def save_atomic(fig, path) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=130, metadata={"CreationDate": None} if path.suffix == ".pdf" else None)
        _publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
