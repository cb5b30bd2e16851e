from .run import RunResult as RunResult
from .run import SweepResult as SweepResult
from .run import simulate as simulate
from .run import simulate_system as simulate_system
from .run import sweep as sweep
from .scenes import SceneResult as SceneResult
from .spectra import spectral_acceleration as spectral_acceleration
