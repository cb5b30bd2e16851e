"""The one set of numerical kernels the study computes with, so that every x86-64 machine gets the same numbers.

OpenBLAS (numpy and scipy each bundle one) and numpy's own vector loops pick their kernels by CPU when they load,
and kernels of different sets round differently: an AVX-512 machine runs OpenBLAS's ``SkylakeX`` kernels and
numpy's AVX-512 loops, an AVX2 one ``Haswell`` kernels and AVX2 loops.  The modal decomposition under every
scene goes through them, and a value that is sensitive to round-off carries their difference to 1e-8 (a CID's
mean impulse under El Centro moves by 1.3e-8 from Haswell to SkylakeX kernels, issue 47).  Held to one set,
AVX2 and FMA (x86-64-v3), the study runs the same instructions on every x86-64 machine that has them, AVX-512
ones included (``docs/performance.md`` measures what that costs).

A set is read once, when its library loads, so :func:`apply` must run before numpy is first imported in a
process.  It does in the workflow (the Snakefile, before any job starts: jobs inherit the environment), the
test run (``tests/conftest.py``) and the command line (``impact``'s entry, ``__main__.py``); any other script
runs under them as ``python -m impact.kernels SCRIPT [ARGS]`` (``make bench`` does).  This module imports the
standard library only, for that reason.

Each pin's ``override`` variable names another set for one run (``native`` leaves the choice to the library):
the round-off ensemble of the smoke fingerprint (``tools/roundoff_ensemble.py``) and the benchmarks of this
policy's cost use them.

OpenBLAS's thread count rounds too: a thread per core splits a matrix product's work another way, and a 10-storey
scene's tables and its peak drift come out different in the last bits with two threads than with one.  Snakemake
gives each of the study's jobs one (its rules ask for one thread, and it sets OpenBLAS's variable to that), so
:func:`apply` gives every other process one as well, the tests and the command line included: they then compute
the study's bits on any machine whatever its core count, and faster (the matrices are small enough that a second
thread waits more than it works; ``docs/performance.md``).
"""

from __future__ import annotations

import os
import platform
import sys
from typing import NamedTuple


class Pin(NamedTuple):
    """One library's kernel set: the variable it reads when it loads, the study's value, and the variable that
    names another value for one run."""

    variable: str
    value: str
    override: str


#: the study's kernel sets, by library
PINS = {
    "openblas": Pin("OPENBLAS_CORETYPE", "Haswell", "IMPACT_OPENBLAS_CORETYPE"),
    # numpy 2.4's name for its AVX2 and FMA loops (its AVX-512 ones are X86_V4 and AVX512_*)
    "numpy": Pin("NPY_ENABLE_CPU_FEATURES", "X86_V3", "IMPACT_NUMPY_CPU_FEATURES"),
}
#: OpenBLAS's threads per process: one, as Snakemake gives each job of the study
THREADS = Pin("OPENBLAS_NUM_THREADS", "1", "IMPACT_OPENBLAS_NUM_THREADS")
#: an override's value that leaves the choice to the library
NATIVE = "native"
#: the CPU features both pinned sets need (x86-64-v3; Linux's names in /proc/cpuinfo)
NEEDS = ("avx2", "fma", "bmi1", "bmi2", "f16c", "movbe", "abm")


def cpu_flags(cpuinfo: str = "/proc/cpuinfo") -> set | None:
    """The CPU's feature flags (Linux's names in /proc/cpuinfo), or None where they cannot be read."""
    try:
        with open(cpuinfo, encoding="ascii", errors="replace") as handle:
            flags = next((line.split(":", 1)[1].split() for line in handle if line.startswith("flags")), None)
    except OSError:
        return None
    return None if flags is None else set(flags)


def _cpu_can_run_it(cpuinfo: str = "/proc/cpuinfo") -> bool:
    """Whether this CPU runs the pinned kernels: x86-64 with NEEDS (assumed where its flags cannot be read)."""
    if platform.machine().lower() not in ("x86_64", "amd64"):
        return False
    flags = cpu_flags(cpuinfo)
    return flags is None or set(NEEDS) <= flags


def chosen(environ=None) -> dict:
    """{library: the set this process should run, or None to leave the choice to the library}: the override
    where one is given, else the pinned set where the CPU runs it."""
    environ = os.environ if environ is None else environ
    runs_pins = _cpu_can_run_it()
    out = {}
    for library, pin in PINS.items():
        named = _named(pin, environ)
        out[library] = (pin.value if runs_pins else None) if named == "" else named
    return out


def _named(pin: Pin, environ) -> str | None:
    """What a pin's override names for this run: a value, None for ``native`` (the library's own choice), or ''
    where it names nothing."""
    wanted = environ.get(pin.override, "").strip()
    return None if wanted.lower() == NATIVE else wanted


def threads(environ=None) -> str | None:
    """OpenBLAS's thread count for this process: the override where one is given (None for ``native``: the
    library's own choice, a thread per core), else THREADS' one, whatever the CPU."""
    named = _named(THREADS, os.environ if environ is None else environ)
    return THREADS.value if named == "" else named


def apply(environ=None) -> dict:
    """Set each library's kernel set and OpenBLAS's thread count (:func:`threads`) in ``environ`` (this process's
    by default, which child processes inherit) and return :func:`chosen`'s answer.  A library left to choose has
    its variable removed, so that no value inherited from the machine decides instead.  In this process it takes
    effect only before numpy loads."""
    environ = os.environ if environ is None else environ
    sets = chosen(environ)
    wanted = [(PINS[library].variable, value) for library, value in sets.items()]
    for variable, value in [*wanted, (THREADS.variable, threads(environ))]:
        if value is None:
            environ.pop(variable, None)
        else:
            environ[variable] = value
    return sets


def pinned(environ=None) -> bool:
    """Whether this process runs the study's own kernel sets and thread count."""
    return (all(value == PINS[library].value for library, value in chosen(environ).items())
            and threads(environ) == THREADS.value)


def kernels() -> str:
    """The kernel sets the loaded libraries run and OpenBLAS's threads, e.g. 'numpy X86_V3; openblas Haswell 1
    thread, openblas Haswell 1 thread' (numpy's loops, then numpy's and scipy's OpenBLAS), for a result's
    provenance: read from the libraries themselves."""
    from numpy._core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    from threadpoolctl import threadpool_info

    loops = [name for name in __cpu_dispatch__ if __cpu_features__.get(name)]
    blas = sorted(f"{info['internal_api']} {info.get('architecture') or 'unknown'} {info['num_threads']} "
                  f"thread{'' if info['num_threads'] == 1 else 's'}"
                  for info in threadpool_info() if info.get("user_api") == "blas")
    return f"numpy {' '.join(loops) or 'baseline'}; {', '.join(blas) or 'no BLAS loaded'}"


def run_script(argv: list[str]) -> None:
    """Run a Python script (``argv[0]``, with its arguments) in this process under the study's kernel sets."""
    import runpy

    if not argv:
        raise SystemExit("usage: python -m impact.kernels SCRIPT [ARGS]: runs SCRIPT under the study's kernel sets")
    apply()
    sys.argv = list(argv)
    sys.path.insert(0, os.path.dirname(os.path.abspath(argv[0])))  # its own folder first, as `python SCRIPT` has
    runpy.run_path(argv[0], run_name="__main__")


if __name__ == "__main__":
    run_script(sys.argv[1:])
