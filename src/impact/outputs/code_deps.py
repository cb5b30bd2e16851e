"""Which library files a workflow script's results depend on, read from the code itself.

Snakemake tracks a rule's script but not what the script imports.  The transitive closure of the ``impact``
modules a script imports (read with :mod:`ast`, imports inside functions included, nothing executed) is the
library code its results can depend on; a digest of those files' syntax trees is a rule's ``library`` param, so an
edit of any of them reruns exactly the jobs whose scripts reach it, and an edit of a comment or of the layout
reruns none.  Data files that ship inside a package the closure imports from (the rig's schema) count as its code.
"""

from __future__ import annotations

import ast
import functools
import hashlib
from pathlib import Path

SRC = Path(__file__).resolve().parents[2]  # the folder that holds this impact package


def data_files(folder: Path) -> set[Path]:
    """The files beside a package's modules that are not Python: its data (pyproject.toml's package-data
    says which ship), read at run time and so part of the code.  Found by looking, so that a copy of the
    workflow without pyproject.toml, or an installed package, finds the same."""
    return {f for f in folder.iterdir() if f.is_file() and f.suffix not in (".py", ".pyc")}


def module_file(name: str, src: Path = SRC) -> Path | None:
    """The source file of an ``impact`` module or package under src, or None for anything else."""
    if name != "impact" and not name.startswith("impact."):
        return None
    base = src.joinpath(*name.split("."))
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _package_of(path: Path, src: Path) -> str:
    """The package a file's relative imports start from ('' for a file outside the library, a script)."""
    if not path.is_relative_to(src):
        return ""
    parts = path.relative_to(src).with_suffix("").parts
    return ".".join(parts[:-1])


def _imported_names(path: Path, src: Path) -> frozenset[str]:
    """Every module an import statement of the file can load (``from a import b``: a, and a.b if b is one)."""
    return _parsed_imports(path, src, _version(path))


def _version(path: Path) -> tuple[int, int]:
    """What a cached reading of a file is keyed by besides its path, so that an edit is read afresh."""
    st = path.stat()
    return st.st_mtime_ns, st.st_size


@functools.cache  # every script's walk meets the same files: each is parsed once per process and version
def _parsed_imports(path: Path, src: Path, version: tuple[int, int]) -> frozenset[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    package = _package_of(path, src)
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
    return frozenset(names)


def _with_parents(name: str) -> list[str]:
    """A module and the packages above it: importing a.b.c runs a/__init__ and a/b/__init__ too."""
    parts = name.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts) + 1)]


def library_files(script: str | Path, src: str | Path = SRC) -> tuple[Path, ...]:
    """The ``impact`` source files under src that the script reaches through its imports, transitively, sorted.

    src: the folder holding the ``impact`` package whose files count (a copy of the workflow has its own).
    """
    return _closure(Path(script).resolve(), Path(src).resolve())


def _closure(script: Path, src: Path) -> tuple[Path, ...]:
    seen: set[Path] = set()
    todo = [script]
    while todo:
        names = _imported_names(todo.pop(), src)
        for name in {p for n in names for p in _with_parents(n)}:
            path = module_file(name, src)
            if path is not None and path not in seen:
                seen.add(path)
                todo.append(path)
    data = set().union(*(data_files(folder) for folder in {p.parent for p in seen}))
    return tuple(sorted(seen | data))


def library_digest(script: str | Path, src: str | Path = SRC) -> str:
    """A content digest of :func:`library_files`: what a rule's ``library`` param holds."""
    src = Path(src).resolve()
    digest = hashlib.sha256()
    for path in library_files(script, src):
        digest.update(path.relative_to(src).as_posix().encode() + b"\0" + _file_digest(path, _version(path)))
    return digest.hexdigest()[:16]


@functools.cache
def _file_digest(path: Path, version: tuple[int, int]) -> bytes:
    """A module's syntax tree (no comments, blank lines or layout, which cannot change what it computes; its
    docstrings count, since code may print them); any other file's bytes."""
    if path.suffix == ".py":
        return hashlib.sha256(ast.dump(ast.parse(path.read_bytes(), filename=str(path))).encode()).digest()
    return hashlib.sha256(path.read_bytes()).digest()
