"""Impact dampers for civil structures: an exact, reproducible study.

The library behind the pipeline: models and parameters (:mod:`impact.model.params`),
the exact event-driven simulator (:mod:`impact.engine.paper`), the TMD reference
(:mod:`impact.closed_form.tmd`) and Masri's closed form (:mod:`impact.closed_form.masri`).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("impact-dampers")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+unknown"
