from .masri import classify as classify
from .masri import masri_2eipc as masri_2eipc
from .tmd import den_hartog as den_hartog
from .tmd_minimax import tmd_optimum as tmd_optimum
