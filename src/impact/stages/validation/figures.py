"""The cross-validation's figures from their data files: the one step that draws (kept apart from the steps
that simulate, so that a change of a figure's style reruns no simulation)."""

from __future__ import annotations

from impact.outputs.validation_figures import plot_fig3, plot_fig5, plot_histories
from impact.stages.validation.steps import read_fig3_data, read_fig5_data


def write_figures(fig3, fig5, fig3_paths, fig5_paths, histories_paths) -> None:
    f5 = read_fig5_data(fig5)
    plot_fig3(read_fig3_data(fig3), fig3_paths)
    plot_fig5(f5, fig5_paths)
    plot_histories(f5, histories_paths)
