"""Glue: the data of Figs. 3 and 5 -> the figures (and Fig. 4's time histories)."""
from impact.experiment.validation import write_figures
from impact.pipeline import logged

with logged(snakemake.log[0]):
    out = snakemake.output
    write_figures(snakemake.input.fig3, snakemake.input.fig5, [out.fig3, out.fig3_pdf], [out.fig5, out.fig5_pdf],
                  [out.histories])
