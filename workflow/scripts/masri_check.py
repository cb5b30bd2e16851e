"""Glue: the closed-form check over a grid -> dataset, table and summary."""
from impact.model.params import Protocol, frequency_grid
from impact.outputs.files import write_csv_atomic, write_dataset, write_json_atomic
from impact.outputs.job_log import job_config, logged
from impact.outputs.provenance import attributes
from impact.stages.masri.check import limits_statement, run_check, summary, to_dataset

with logged(snakemake.log[0]) as log:
    p = snakemake.params
    g = p.grid["gap"]
    grid = {"mu": p.grid["mu"], "e": p.grid["e"], "r": p.grid["r"],
            "gap_ratio": frequency_grid(g["min"], g["max"], g["step"]).tolist()}
    protocol = Protocol(periods=p.protocol["periods"], average_from=p.protocol["average_from"])
    table = run_check(grid, p.structure["beta"], p.structure["force_ratio"], p.starts, protocol)
    result = {"summary": summary(table, p.starts), "limits": limits_statement(table, p.starts)}
    log.info("%s", result)
    attrs = {"title": "Masri's closed-form 2-EIPC orbit against the exact simulator",
             "beta": p.structure["beta"], "force_ratio": p.structure["force_ratio"], **attributes()}
    write_dataset(to_dataset(table, attrs), snakemake.output.dataset, config=job_config(snakemake))
    write_csv_atomic(snakemake.output.table, table[table["admissible"]])
    write_json_atomic(snakemake.output.summary, result)
