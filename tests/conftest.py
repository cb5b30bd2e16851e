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


@pytest.fixture(scope="module")
def tool(request):
    """The script tools/<name>.py that a test module names in its TOOL, loaded as a module (tools/ is no package)."""
    path = Path(request.module.TOOL)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
