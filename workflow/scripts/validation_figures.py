"""Glue: the data of Figs. 3 and 5 -> the figures (and Fig. 4's time histories)."""
from impact.outputs.job_log import logged
from impact.stages.validation.figures import write_figures

with logged(snakemake.log[0]):
    out = snakemake.output
    write_figures(snakemake.input.fig3, snakemake.input.fig5, [out.fig3, out.fig3_pdf], [out.fig5, out.fig5_pdf],
                  [out.histories])
