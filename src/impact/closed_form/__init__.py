"""Answers without simulation: Masri's two-impacts-per-cycle orbit and its stability, the TMD's optimum, a linear
building's exact discrete propagator under a record.

The public names load on first use (``__init__.pyi`` lists them).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
