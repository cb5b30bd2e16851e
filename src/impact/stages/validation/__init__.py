"""The cross-validation stage: the virtual rig, the paper's Eq. (4) model, their measurements and analysis.

- :mod:`.measurements`  the measurement file format (``docs/experiment-data.md``), a validating loader, a writer
- :mod:`.analysis`      the paper's analysis chain (Sect. 3): log decrement, half-power damping, sqrt(2) RMS
                        amplitudes, restitution from drop tests, impact counting
- :mod:`.grid`          the rig's configuration (``rig.schema.yaml``) and its grid of cases
- :mod:`.rig`           the virtual rig, a higher-fidelity model of the paper's test stand
- :mod:`.paper_model`   the paper's Eq. (4) model, run by the engine and sampled into measurements
- :mod:`.comparison`    model against rig, case by case
- :mod:`.claims`        the paper's Sect. 3 claims as the two sources see them
- :mod:`.plotting`      the stage's figures (the paper's Figs. 3 to 5)
- :mod:`.steps`         the stage's steps as the workflow runs them, each reading and writing files
- :mod:`.figures`       the step that draws the figures from their data files
- :mod:`.standalone`    every step in one process, outside the workflow
"""
