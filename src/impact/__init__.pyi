from .closed_form import den_hartog as den_hartog
from .closed_form import masri_2eipc as masri_2eipc
from .closed_form import tmd_optimum as tmd_optimum
from .engine import RunResult as RunResult
from .engine import SceneResult as SceneResult
from .engine import SweepResult as SweepResult
from .engine import simulate as simulate
from .engine import spectral_acceleration as spectral_acceleration
from .engine import sweep as sweep
from .model import Building as Building
from .model import Damper as Damper
from .model import ForceRecord as ForceRecord
from .model import GroundMotion as GroundMotion
from .model import Harmonic as Harmonic
from .model import ParameterError as ParameterError
from .model import Protocol as Protocol
from .model import Record as Record
from .model import RecordError as RecordError
from .model import Scene as Scene
from .model import System as System
from .model import kanai_tajimi as kanai_tajimi
from .model import load_record as load_record
from .model import narrow_band_force as narrow_band_force
from .model import paper_scene as paper_scene
from .model import record_by_key as record_by_key
from .model import suite_keys as suite_keys

__version__: str
