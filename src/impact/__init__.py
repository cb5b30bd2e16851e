"""Impact dampers for civil structures: an exact, reproducible study.

The library behind the pipeline: models and parameters (:mod:`impact.params`),
the exact event-driven simulator (:mod:`impact.simulate`), the TMD reference
(:mod:`impact.tmd`) and Masri's closed form (:mod:`impact.masri`).
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("impact-dampers")
except PackageNotFoundError:  # running from a source tree without install
    __version__ = "0.0.0+unknown"
