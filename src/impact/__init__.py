"""Impact dampers for civil structures: an exact, reproducible study.

The library behind the pipeline, in layers (``docs/architecture.md``): :mod:`impact.model` (what is simulated:
the paper's :class:`System` and :class:`Protocol`, a :class:`Building` with :class:`Damper` units under a load, a
:class:`Scene`, records), :mod:`impact.engine` (the exact event-driven simulator: :func:`simulate`, :func:`sweep`),
:mod:`impact.closed_form` (Masri's 2-EIPC orbit, the TMD's optimum), then the baselines, the outputs and the study's
stages.  The names of the first three are re-exported here::

    from impact import Building, Damper, GroundMotion, Scene, load_record, simulate

They load on first use (scientific Python's SPEC 1, by ``lazy_loader``; the names are in ``__init__.pyi``, which
type checkers read): ``impact --help``, the workflow's start and a script that only builds a model load neither
numba nor the FEMA P695 suites.
"""

from importlib.metadata import PackageNotFoundError, version

import lazy_loader

try:
    __version__ = version("impact-dampers")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+unknown"

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
__all__ = [*__all__, "__version__"]
