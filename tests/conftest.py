import sys
from pathlib import Path

from impact import kernels

# the study's kernel sets (impact.kernels), before numpy first loads in this process, and for every process
# the tests start (the smoke study's jobs too)
kernels.apply()

sys.path.insert(0, str(Path(__file__).parent))
