"""The masri stage: Masri's two-impacts-per-cycle closed form against the engine.

- :mod:`.charts`  the closed form alone: the stability chart over (r, d) and both roots along r
- :mod:`.check`   the closed-form orbits run on the engine: stable ones kept, unstable ones left, runs from rest
"""
