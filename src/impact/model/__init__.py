"""What is simulated: parameters and their checks, the paper's system and protocol, buildings, dampers, loads
and records, the scene.  Plain Python and numpy: importing it compiles nothing (the engine does that).
"""
