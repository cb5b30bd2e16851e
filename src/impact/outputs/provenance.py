"""Where a result came from: code version, git state, package versions, time."""

from __future__ import annotations

import datetime as _dt
import functools
import platform
import subprocess
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from impact import __version__, kernels

_REPO = Path(__file__).resolve().parents[3]
PACKAGES = ("numpy", "scipy", "numba", "xarray", "netCDF4", "pandas", "matplotlib", "snakemake")


def _git(*args: str) -> str | None:
    try:
        out = subprocess.run(["git", *args], cwd=_REPO, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


@functools.lru_cache(maxsize=1)
def git_state() -> dict:
    """Commit of the source tree and whether it has uncommitted changes to tracked files."""
    commit = _git("rev-parse", "HEAD") or "unknown"
    status = _git("status", "--porcelain", "--untracked-files=no")
    dirty = "unknown" if status is None else ("yes" if status else "no")
    return {"git_commit": commit, "git_dirty": dirty}


def package_versions() -> dict:
    out = {"python": platform.python_version()}
    for name in PACKAGES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            continue
    return out


def now_utc() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def attributes() -> dict:
    """Global attributes every dataset of the study carries."""
    state = git_state()
    return {
        "source": f"impact-dampers {__version__} (exact event-driven simulator)",
        "code_version": __version__,
        "git_commit": state["git_commit"],
        "git_dirty": state["git_dirty"],
        "date_created": now_utc(),
        "kernels": kernels.kernels(),
    }
