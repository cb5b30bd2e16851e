"""Spectral acceleration by the exact core: the intensity measure Sa(T, zeta) of a ground motion.

A record is piecewise linear between its samples, and the core's flow over each sample step is the closed-form
solution of the linear oscillator under that ramp; its peak search finds the extremum inside a step, not only at
the samples.  So Sa(T) = (2 pi / T)^2 max |u(t)| of a one-storey building of period T and damping ratio zeta,
run on the same engine as every scene, is exact to round-off for the record as given: no sub-stepping, no
interpolation error.  (The pseudo-acceleration, the convention of design spectra and of FEMA P695.)
"""

from __future__ import annotations

import math

from impact.engine.scenes import simulate_scene
from impact.model.building import Building
from impact.model.params import G_GRAV, ParameterError
from impact.model.records import Record
from impact.model.scene import GroundMotion, Scene

SPECTRUM_DAMPING = 0.05   # the design spectra's damping ratio (ASCE 7, FEMA P695)


def spectral_acceleration(record: Record, period_s: float, zeta: float = SPECTRUM_DAMPING) -> float:
    """Sa(period_s, zeta) of the record as given, in g (pseudo-acceleration: omega^2 times the peak displacement).

    The oscillator runs over the record's length only: FEMA P695's spectra, like ours, take the peak during the
    motion (a lightly damped long-period oscillator can peak in free vibration after it; not counted here).
    """
    if not (isinstance(period_s, (int, float)) and math.isfinite(period_s) and 0.0 < period_s <= 100.0):
        raise ParameterError(f"period_s = {period_s!r} is out of range: allowed (0, 100] s")
    if not record.pga_g > 0.0:
        raise ParameterError(f"record {record.name!r} is zero at every sample: its spectral acceleration is 0 at "
                             "every period, so it cannot be scaled to an intensity")
    oscillator = Building.uniform(1, period_s, zeta)
    load = GroundMotion.from_record(record)
    peak = simulate_scene(Scene(oscillator, (), load, duration=load.duration), peaks=("roof",)).peak_roof_displacement
    return (2.0 * math.pi / period_s) ** 2 * peak / G_GRAV
