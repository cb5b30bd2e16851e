"""Keep numba's on-disk cache honest across modules.

numba checks only the source file of the function it loads from its cache,
but a kernel carries compiled copies of the functions it calls from other
modules: after an edit of segment.py alone, run_scene (scene_loop.py) or the
paper loop (paper_loop.py, which shares the contact search of events.py) would
load stale code.  A stamp of the sources the kernels are compiled from
(:func:`kernel_sources`), kept beside each cache, catches that and drops the
cached kernels of that folder once.

:func:`compile_lock` serialises compiling and loading of one kernel across
processes (two kernels compile side by side, one a core), and is where a stale
cache is dropped: every call of a cached kernel goes through it the first time
in a process, and nothing is deleted merely by importing.  numba's own write
of a function's cache index is serialised apart (:func:`_serialised_save`),
since kernels compiled side by side share the steps they call.
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
from numba.core import caching as numba_caching

CORE = Path(__file__).parent
# the stamp's name in a cache folder: one per folder, so two loops caching in one folder share it (with one
# each, the second loop to load after an edit would purge what the first had just compiled)
STAMP = "impact-sources"
# the lock of a whole cache folder, taken briefly: to drop a stale cache, and for each write of a function's index
FOLDER_LOCK = "impact-jit.lock"


# an engine module's imports of other engine modules: `from impact.engine.<module> import ...`, or
# `from impact.engine import <module> [as x], ...` (on one line or in parentheses); a regular expression, since
# parsing the sources costs every process a tenth of a second before its first kernel
_FROM_MODULE = re.compile(r"^\s*from impact\.engine\.(\w+) import", re.MULTILINE)
_FROM_ENGINE = re.compile(r"^\s*from impact\.engine import (\([^)]*\)|[^\n]*)", re.MULTILINE)
# (an import of numba's caching alone, this module's, keeps the cache and adds nothing to what kernels compute)
_USES_NUMBA = re.compile(r"^\s*(import numba|from numba[ .])(?!.*\bcaching\b)", re.MULTILINE)


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
    """Exclusive lock on one kernel of the numba cache folder while it compiles or loads.

    Processes starting together (parallel Snakemake or SLURM jobs, `impact compile`'s workers) never compile
    one kernel twice: the first compiles and stores it, the others wait and then load, while a process wanting
    another kernel compiles that one beside it.  (filelock: a well-kept lock that also works where fcntl does
    not.)

    what: a short name of the kernels the block compiles or loads (safe in a file name; None: the block only
    drops a stale cache), label: what a person reads.  The first time they compile for these sources, one line on
    stderr says so, since it takes a minute or two and happens once: later processes load them from the cache.
    fresh: the dispatchers the block calls, whose caches are dropped first if the engine's sources changed since
    they were written.
    """
    folder = _cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    with filelock.FileLock(folder / FOLDER_LOCK):
        for dispatcher in fresh:
            purge_stale_cache(dispatcher)
    if what is None:
        yield
        return
    stamp = folder / f"compiled-{what}-{sources_digest()}.stamp"
    with filelock.FileLock(folder / f"impact-jit-{what}.lock"):
        if not stamp.exists():
            _say(f"impact: compiling {label or what} (once: later runs load it from {folder}; this takes a minute "
                 "or two)")
        yield
        with contextlib.suppress(OSError):  # a read-only cache: numba compiled in memory
            stamp.touch()


def _serialised_save(save):
    """numba writes a function's cache index by reading it, adding the new overload and writing it back, and names
    the overload's data file by the index it read.  Two kernels compiling side by side compile the steps they share
    each for its own types, so two processes may save to one index at once: each would write it without the other's
    overload, or give two overloads one data file.  Under the folder's lock the second save reads the first's
    index."""

    @functools.wraps(save)
    def locked(self, key, data):
        with filelock.FileLock(Path(self._cache_path) / FOLDER_LOCK):
            save(self, key, data)

    locked.serialised = True
    return locked


if not getattr(numba_caching.IndexDataCacheFile.save, "serialised", False):
    numba_caching.IndexDataCacheFile.save = _serialised_save(numba_caching.IndexDataCacheFile.save)


def _say(line: str) -> None:
    """One line on stderr, and on the terminal too when a workflow job sends its stderr to its log file (a
    first compile under Snakemake would otherwise be minutes of silence)."""
    print(line, file=sys.stderr, flush=True)
    if sys.stderr is not sys.__stderr__ and sys.__stderr__ is not None:
        print(line, file=sys.__stderr__, flush=True)
