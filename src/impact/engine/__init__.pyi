from .paper import RunResult as RunResult
from .paper import SweepResult as SweepResult
from .paper import sweep as sweep
from .run import simulate as simulate
from .scenes import SceneResult as SceneResult
from .spectra import spectral_acceleration as spectral_acceleration
