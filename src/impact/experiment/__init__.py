"""Experiment records and the paper's analysis chain (Chua et al., Sect. 3).

:mod:`impact.experiment.records` defines the record format (one CSV or netCDF
file per run, ``docs/experiment-data.md``), a validating loader and an atomic
writer; :mod:`impact.experiment.analysis` the analysis: log decrement from
free decay, half-power damping from a sweep, sqrt(2)*RMS amplitudes,
restitution from drop tests (Eq. 3b) and impact counting.
"""

from .analysis import (
    ASSUMED_SENSOR_NOISE_MM,
    HalfPower,
    ImpactCount,
    LogDecrement,
    SweepCurve,
    UnresolvedPeakError,
    beta_to_delta,
    count_impacts,
    delta_to_beta,
    dominant_frequency,
    drop_test_restitution,
    free_decay_delta,
    half_power,
    half_power_damping,
    impacts_per_cycle,
    log_decrement,
    rebound_height,
    restitution_from_drop,
    steady_amplitude,
    sweep_curve,
    whole_periods,
)
from .records import (
    HEADER_FIELDS,
    KINDS,
    Record,
    RecordError,
    load_record,
    load_records,
    make_record,
    validate_header,
    write_record,
)

__all__ = [
    "ASSUMED_SENSOR_NOISE_MM", "HEADER_FIELDS", "KINDS", "HalfPower", "ImpactCount", "LogDecrement",
    "Record", "RecordError", "SweepCurve", "UnresolvedPeakError", "beta_to_delta", "count_impacts",
    "delta_to_beta", "dominant_frequency", "drop_test_restitution", "free_decay_delta", "half_power",
    "half_power_damping", "impacts_per_cycle", "load_record", "load_records", "log_decrement",
    "make_record", "rebound_height", "restitution_from_drop", "steady_amplitude", "sweep_curve",
    "validate_header", "whole_periods", "write_record",
]
