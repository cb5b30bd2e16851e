import importlib.util
import sys
from pathlib import Path

import pytest

from impact import kernels

# the study's kernel sets (impact.kernels), before numpy first loads in this process, and for every process
# the tests start (the smoke study's jobs too)
kernels.apply()

sys.path.insert(0, str(Path(__file__).parent))


def pytest_sessionstart(session):
    """Tests call the engine's compiled steps directly (events, segment), not only through the loops' compile
    lock, so a cache written before an edit of another engine file is dropped here, once, under that lock."""
    from impact.engine import jitcache, scene_loop

    with jitcache.compile_lock(fresh=(scene_loop.run_scene,)):
        pass


def pytest_collection_modifyitems(items):
    """The files marked long_file first, the longest first, the rest in their order: with a file to a worker
    (`make test`: xdist's --dist loadfile, in collection order), a file of many minutes started last would leave one
    worker running it alone at the end.  (A file's minutes, measured on 2 workers on 2026-12-02, are a schedule's
    hint, not a promise.)"""
    items.sort(key=lambda item: -_long_file_minutes(item))


def _long_file_minutes(item) -> float:
    mark = item.get_closest_marker("long_file")
    return mark.kwargs["minutes"] if mark else 0.0


@pytest.fixture(scope="module")
def tool(request):
    """The script tools/<name>.py that a test module names in its TOOL, loaded as a module (tools/ is no package)."""
    path = Path(request.module.TOOL)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
