"""Experiment records and the paper's analysis chain (Chua et al., Sect. 3).

:mod:`impact.experiment.records` defines the record format (one CSV or netCDF
file per run, ``docs/experiment-data.md``), a validating loader and an atomic
writer; :mod:`impact.experiment.analysis` the analysis: log decrement from
free decay, half-power damping from a sweep, sqrt(2)*RMS amplitudes,
restitution from drop tests (Eq. 3b) and impact counting.
"""

import importlib

# The names below load their module on first use (PEP 562): the analysis needs scipy.signal and
# scipy.stats (about 1 s to import), which the workflow's own start-up (it reads the grid) and the
# jobs that only write records should not pay.
_SOURCES = {
    ".analysis": (
        "ASSUMED_SENSOR_NOISE_MM", "HalfPower", "ImpactCount", "LogDecrement", "SweepCurve", "UnresolvedPeakError",
        "beta_to_delta", "count_impacts", "delta_to_beta", "dominant_frequency", "drop_test_restitution",
        "free_decay_delta", "half_power", "half_power_damping", "impacts_per_cycle", "log_decrement",
        "rebound_height", "restitution_from_drop", "steady_amplitude", "sweep_curve", "whole_periods",
    ),
    ".records": (
        "HEADER_FIELDS", "KINDS", "Record", "RecordError", "load_record", "load_records", "make_record",
        "validate_header", "write_record",
    ),
}
_MODULE_OF = {name: module for module, names in _SOURCES.items() for name in names}


def __getattr__(name):
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


__all__ = sorted(_MODULE_OF)
