import sys
from pathlib import Path

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
