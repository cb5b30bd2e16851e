"""The cross-validation stage: the paper's Eq. (4) model against the virtual rig, case by case.

The rig itself is :mod:`impact.rig`, the measurement format :mod:`impact.outputs.measurements`, the paper's
analysis chain (log decrement, half-power damping, RMS amplitudes, restitution from drop tests, impact counting)
:mod:`impact.outputs.signals` and the figures :mod:`impact.outputs.validation_figures`; this stage holds only
its plan, its runs and its tables:

- :mod:`.grid`          the grid of cases
- :mod:`.paper_model`   the paper's Eq. (4) model, run by the engine and sampled into measurements
- :mod:`.comparison`    model against rig, case by case
- :mod:`.claims`        the paper's Sect. 3 claims as the two sources see them
- :mod:`.steps`         the stage's steps as the workflow runs them, each reading and writing files
- :mod:`.figures`       the step that draws the figures from their data files
- :mod:`.standalone`    every step in one process, outside the workflow
"""
