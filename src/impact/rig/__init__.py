"""The virtual test rig: a higher-fidelity model of the paper's test stand, which the engine is checked against.

It is an independent simulator beside the engine's baselines (:mod:`impact.baselines`), with its own contact law
(compliant walls calibrated to each material's restitution), its own integrator and its own configuration:

- :mod:`.config`     the rig's configuration: ``rig.schema.yaml`` beside it holds every default, unit and
                     allowed range; ``validation_config`` fills them in and refuses a bad value by name
- :mod:`.simulator`  the rig's model, its runs (forced points, free decays, drop tests) and their records in the
                     measurement format (:mod:`impact.outputs.measurements`)

The cross-validation stage (:mod:`impact.stages.validation`) plans the cases, runs both sides and compares them.
"""
