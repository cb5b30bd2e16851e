"""Keep numba's on-disk cache honest across modules.

numba checks only the source file of the function it loads from its cache,
but a kernel carries compiled copies of the functions it calls from other
modules: after an edit of segment.py alone, run_scene (scene_loop.py) or the
paper loop (paper_loop.py, which shares the contact search of events.py) would
load stale code.  A stamp of the sources the kernels are compiled from
(:func:`kernel_sources`), kept beside each cache, catches that and drops the
cached kernels of that folder once.

:func:`compile_lock` serialises compiling and loading across processes, and is
where a stale cache is dropped: every call of a cached kernel goes through it
the first time in a process, and nothing is deleted merely by importing.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import re
import sys
from pathlib import Path

import filelock

CORE = Path(__file__).parent
# the stamp's name in a cache folder: one per folder, so two loops caching in one folder share it (with one
# each, the second loop to load after an edit would purge what the first had just compiled)
STAMP = "impact-sources"


# an engine module's imports of other engine modules: `from impact.engine.<module> import ...`, or
# `from impact.engine import <module> [as x], ...` (on one line or in parentheses); a regular expression, since
# parsing the sources costs every process a tenth of a second before its first kernel
_FROM_MODULE = re.compile(r"^\s*from impact\.engine\.(\w+) import", re.MULTILINE)
_FROM_ENGINE = re.compile(r"^\s*from impact\.engine import (\([^)]*\)|[^\n]*)", re.MULTILINE)
_USES_NUMBA = re.compile(r"^\s*(import numba|from numba[ .])", re.MULTILINE)


def _engine_imports(text: str) -> set[str]:
    """The engine's modules that a module of the engine imports."""
    names = set(_FROM_MODULE.findall(text))
    for group in _FROM_ENGINE.findall(text):
        names.update(part.split(" as ")[0].strip() for part in group.strip("()").split(","))
    return {name for name in names if (CORE / f"{name}.py").exists()}


def kernel_sources() -> list[Path]:
    """The engine's modules whose code and constants the kernels are compiled from: those that import numba, and
    the engine's modules they import, transitively.  The Python around the kernels (run.py's dispatch, scenes.py's
    arrays and results) is not among them, so an edit there keeps the compiled kernels, which take a quarter of an
    hour to make again."""
    modules = {path.stem: path for path in CORE.glob("*.py")}
    texts = {name: path.read_text() for name, path in modules.items()}
    imports = {name: _engine_imports(text) for name, text in texts.items()}
    numba_users = {name for name, text in texts.items() if _USES_NUMBA.search(text)}
    kernels, todo = set(), list(numba_users)
    while todo:
        name = todo.pop()
        if name not in kernels:
            kernels.add(name)
            todo.extend(imports[name])
    return [modules[name] for name in sorted(kernels)]


@functools.cache  # every compile_lock reads it; the sources are read once per process
def sources_digest() -> str:
    digest = hashlib.sha256()
    for src in kernel_sources():
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
