"""What is simulated: parameters and their checks, the paper's system and protocol, buildings, dampers, loads
and records, the scene.  Plain Python and numpy: importing it compiles nothing (the engine does that).

The public names load on first use (``__init__.pyi`` lists them).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
