"""Small helpers for the Snakemake scripts (kept here so the scripts stay glue)."""

from __future__ import annotations

import contextlib
import json
import logging
import sys
import time
from pathlib import Path

from impact.outputs.provenance import attributes, package_versions


@contextlib.contextmanager
def logged(path):
    """Send this job's logging, stdout and stderr to its log file; log the run time."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as stream:
        handler = logging.StreamHandler(stream)
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
        root = logging.getLogger()
        root.addHandler(handler)
        root.setLevel(logging.INFO)
        start = time.perf_counter()
        with contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
            try:
                yield logging.getLogger("impact")
                logging.info("done in %.2f s", time.perf_counter() - start)
            except BaseException:
                logging.exception("failed after %.2f s", time.perf_counter() - start)
                raise
            finally:
                root.removeHandler(handler)


def log_versions() -> None:
    logging.info("python %s; %s", sys.version.split()[0], json.dumps(package_versions()))
    logging.info("provenance %s", json.dumps(attributes()))


def job_config(smk) -> dict:
    """What a job's results depend on, beside the library code: its rule's params (the `config` attribute
    write_dataset keeps)."""
    return {name: value for name, value in smk.params.items() if name != "library"}
