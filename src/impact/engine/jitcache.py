"""Keep numba's on-disk cache honest across modules.

numba checks only the source file of the function it loads from its cache,
but a kernel carries compiled copies of the functions it calls from other
modules: after an edit of segment.py alone, run_scene (scene_loop.py) or the
paper loop (paper_loop.py, which shares the contact search of events.py) would
load stale code.  A stamp of the engine's sources, kept beside each cache,
catches that and drops the cached kernels of that folder once.

:func:`compile_lock` serialises compiling and loading across processes, and is
where a stale cache is dropped: every call of a cached kernel goes through it
the first time in a process, and nothing is deleted merely by importing.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import sys
from pathlib import Path

import filelock

CORE = Path(__file__).parent
# the stamp's name in a cache folder: one per folder, so two loops caching in one folder share it (with one
# each, the second loop to load after an edit would purge what the first had just compiled)
STAMP = "impact-sources"


@functools.cache  # every compile_lock reads it; the sources are read once per process
def sources_digest() -> str:
    digest = hashlib.sha256()
    for src in sorted(CORE.glob("*.py")):
        digest.update(src.name.encode() + src.read_bytes())
    return digest.hexdigest()[:16]


def purge_stale_cache(dispatcher) -> None:
    """Drop the cached kernels beside `dispatcher`'s cache when the core's sources changed.

    Called under :func:`compile_lock` (which serialises it across processes), before the dispatcher loads.
    """
    if not hasattr(dispatcher, "_cache"):
        return  # NUMBA_DISABLE_JIT: plain Python functions, nothing cached
    folder = Path(dispatcher._cache._cache_path)
    stamp = folder / f"{STAMP}-{sources_digest()}.stamp"
    try:
        if stamp.exists():
            return
        folder.mkdir(parents=True, exist_ok=True)
        for old in folder.iterdir():
            stale_stamp = old.suffix == ".stamp" and old.name.startswith(("impact-", "compiled-"))
            if old.suffix in (".nbi", ".nbc") or stale_stamp:
                old.unlink(missing_ok=True)
        stamp.touch()
    except OSError:
        pass  # a read-only cache: numba compiles in memory instead


def _cache_dir() -> Path:
    return Path(os.environ.get("NUMBA_CACHE_DIR") or CORE / "__pycache__")


@contextlib.contextmanager
def compile_lock(what: str | None = None, label: str = "", fresh=()):
    """Exclusive lock on the numba cache folder while kernels compile or load.

    Processes starting together (parallel Snakemake or SLURM jobs) never write
    the on-disk cache at the same time: the first compiles and stores, the
    others wait and then load.  (filelock: a well-kept lock that also works
    where fcntl does not.)

    what: a short name of the kernels the block compiles or loads (safe in a
    file name), label: what a person reads.  The first time they compile for
    these sources, one line on stderr says so, since it takes a minute or two
    and happens once: later processes load them from the cache.  fresh: the
    dispatchers the block calls, whose caches are dropped first if the
    engine's sources changed since they were written.
    """
    folder = _cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    stamp = folder / f"compiled-{what}-{sources_digest()}.stamp" if what else None
    with filelock.FileLock(folder / "impact-jit.lock"):
        for dispatcher in fresh:
            purge_stale_cache(dispatcher)
        if stamp is not None and not stamp.exists():
            _say(f"impact: compiling {label or what} (once: later runs load it from {folder}; this takes a minute "
                 "or two)")
        yield
        if stamp is not None:
            with contextlib.suppress(OSError):  # a read-only cache: numba compiled in memory
                stamp.touch()


def _say(line: str) -> None:
    """One line on stderr, and on the terminal too when a workflow job sends its stderr to its log file (a
    first compile under Snakemake would otherwise be minutes of silence)."""
    print(line, file=sys.stderr, flush=True)
    if sys.stderr is not sys.__stderr__ and sys.__stderr__ is not None:
        print(line, file=sys.__stderr__, flush=True)
