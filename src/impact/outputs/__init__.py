"""What the study leaves behind: atomic files and datasets, provenance, job logs, figures, the report, the
archive.  Below the stages: nothing here imports a stage."""
