"""Small helpers for the Snakemake scripts (kept here so the scripts stay glue)."""

from __future__ import annotations

import contextlib
import json
import logging
import os
import sys
import tempfile
import time
from pathlib import Path


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


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def publish(tmp, path) -> None:
    """Give a finished temporary file ordinary permissions and move it into place."""
    os.chmod(tmp, 0o666 & ~_umask())
    os.replace(tmp, path)



def write_text_atomic(path, text: str) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w") as fh:
            fh.write(text)
        publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_json_atomic(path, obj) -> None:
    write_text_atomic(path, json.dumps(obj, indent=1, sort_keys=True) + "\n")


def write_csv_atomic(path, frame) -> None:
    write_text_atomic(path, frame.to_csv(index=False))


def log_versions() -> None:
    from .provenance import attributes, package_versions

    logging.info("python %s; %s", sys.version.split()[0], json.dumps(package_versions()))
    logging.info("provenance %s", json.dumps(attributes()))
