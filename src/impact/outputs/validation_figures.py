"""The cross-validation's figures (the paper's Figs. 3, 4 and 5), drawn from their data files only."""

from __future__ import annotations

from pathlib import Path

# pyplot as the outputs layer sets it up, on the file-only Agg backend (no display on a cluster node)
from impact.model.kinds import PID
from impact.outputs.plotting import plt, save_atomic


def _sweep_axes(ax, title):
    ax.set_xlabel("frequency ratio r")
    ax.set_ylabel("√2·RMS amplitude [mm]")
    ax.set_title(title)


def _finish(fig, paths, axes=()) -> list[Path]:
    """Legends and grids on `axes`, the synthetic-data note, then write every path and close."""
    for ax in axes:
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.suptitle(SYNTH_NOTE, fontsize=8)
    fig.tight_layout()
    out = _save(fig, paths)
    plt.close(fig)
    return out


def _save(fig, paths) -> list[Path]:
    out = []
    for p in paths:
        save_atomic(fig, p)
        out.append(Path(p))
    return out


SYNTH_NOTE = "synthetic: virtual rig vs Eq. (4) model -- not the paper's measurements"


def plot_fig3(data: dict, paths) -> list[Path]:
    """Fig. 3 analogue: (a) delta vs amplitude of the bare structure's free decays; (b) sweep + half-power."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    dec = data["decay"]
    rig = dec[dec.source == "rig"]
    ax1.plot(rig.amplitude_mm, rig.delta, ".", ms=3, color="C0", label="virtual rig (per cycle)")
    ax1.axhline(data["delta_exact"], color="k", lw=1.2, label=f"model δ = {data['delta_exact']:.4f}")
    ax1.axhline(data["delta_mean"]["rig"], color="C0", ls="--", lw=1,
                label=f"rig mean δ = {data['delta_mean']['rig']:.4f}")
    ax1.axvline(5.0, color="0.6", ls=":", lw=1)
    ax1.set_xlabel("displacement amplitude [mm]")
    ax1.set_ylabel("log decrement δ")
    ax1.set_title("(a) bare structure, free vibration")
    sc = data["steady_curve"]
    ax2.plot(sc["r"], sc["amp_mm"], "-", color="k", lw=1, label="model, steady state")
    styles = {"paper_grid": ("o", "C1"), "fine_grid": (".", "C0")}
    for g, sw in data["sweeps"].items():
        m, c = styles[g]
        hp = sw["half_power"]["rig"]
        lab = f"rig, step {sw['step']:g}: " + (f"β_hp = {hp['beta']:.5f}" if hp["resolved"] else "β unresolved")
        ax2.plot(sw["r"], sw["rig_amp_mm"], m, ms=4, color=c, mfc="none", label=lab)
    _sweep_axes(ax2, "(b) bare structure, forced vibration")
    ax2.set_xlim(0.97, 1.03)
    return _finish(fig, paths, (ax1, ax2))


def plot_fig5(data: dict, paths) -> list[Path]:
    """Fig. 5 analogue: (a) delta - delta_bare vs amplitude (steel walls); (b) sweep (1.0 mm rubber)."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    a = data["a"]["data"]
    for who, m, c in (("rig", ".", "C0"), ("model", "x", "C3")):
        sel = (a.source == who) & (a.system == PID)
        ax1.plot(a.loc[sel, "amplitude_mm"], a.loc[sel, "delta_minus_bare"], m, ms=3, color=c,
                 label=f"{who}, with PID")
        sel = (a.source == who) & (a.system == "bare")
        ax1.plot(a.loc[sel, "amplitude_mm"], a.loc[sel, "delta_minus_bare"], m, ms=2, color="0.6",
                 label=f"{who}, bare" if who == "rig" else None)
    ax1.axhline(0.0, color="k", lw=0.8)
    ax1.set_xlabel("displacement amplitude [mm]")
    ax1.set_ylabel("δ − δ_bare")
    ax1.set_title(f"(a) free vibration, {data['a']['case']}")
    b = data["b"]["data"].sort_values("r")
    ax2.plot(b.r, b.model_amp_mm, "-", color="C3", lw=1.2, label="model Eq. (4)")
    ax2.plot(b.r, b.rig_amp_mm, "o", ms=4, mfc="none", color="C0", label="virtual rig")
    beat = b.rig_beating.astype(bool)
    ax2.plot(b.r[beat], b.rig_amp_mm[beat], "o", ms=4, color="C0", label="rig record beats")
    for r_show in data["b"]["histories"]:
        ax2.axvline(r_show, color="0.7", ls=":", lw=1)
    _sweep_axes(ax2, f"(b) forced vibration, {data['b']['case']}")
    return _finish(fig, paths, (ax1, ax2))


def plot_histories(data: dict, paths) -> list[Path]:
    """Fig. 4 analogue: the rig's and the model's records at the Fig. 5(b) extra points."""
    hist = data["b"]["histories"]
    n = max(len(hist), 1)
    fig, axes = plt.subplots(n, 1, figsize=(9, 2.2 * n), squeeze=False)
    for ax, (r_show, h) in zip(axes[:, 0], sorted(hist.items())):
        ax.plot(h["rig"]["t"], h["rig"]["x"], lw=0.5, color="C0", label="virtual rig")
        ax.plot(h["model"]["t"], h["model"]["x"], lw=0.5, color="C3", alpha=0.7, label="model")
        ax.set_ylabel("x [mm]")
        ax.set_title(f"r = {r_show:g}", fontsize=9)
    axes[-1, 0].set_xlabel("t [s]")
    axes[0, 0].legend(fontsize=7, loc="upper right")
    return _finish(fig, paths)
