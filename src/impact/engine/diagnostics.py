"""A run's diagnostics array as named numbers: counters, penetration and the energy balance.

Both loops of the engine write their diagnostics into a float64 vector whose indices their layout module names;
:func:`read_diagnostics` turns it into a dict with the same keys for either.
"""

from __future__ import annotations


def energy_balance(work: float, viscous: float, impact_losses: float, friction: float, e0: float, e1: float,
                   e_max: float) -> dict:
    """A run's energy terms and the residual of its balance, work - losses - (E1 - E0).

    The residual is normalised by the largest energy in play (the work, the losses or the most the run
    stored), so that a run that stores far more than it exchanges (no damping, a mass started at a far
    wall) is judged on the right scale.
    """
    losses = viscous + impact_losses + friction
    residual = work - losses - (e1 - e0)
    scale = max(abs(work), losses, e_max, 1e-300)
    return {"energy_residual": float(residual / scale), "work_input": float(work),
            "viscous_dissipation": float(viscous), "impact_losses": float(impact_losses),
            "friction_work": float(friction)}


# A kernel's diagnostics as named numbers: the name, its index's name in the kernel's layout, the type.
# Each kernel reports the fields its layout defines, so the two kernels share one reader.
_DIAGNOSTIC_FIELDS = (
    ("impacts", "D_IMPACTS", int),
    ("impacts_in_window", "D_IMPACTS_WIN", int),
    ("simultaneous_impact_events", "D_SIMULTANEOUS", int),
    ("sticking_episodes", "D_STICKS", int),
    ("grazing_events", "D_GRAZE", int),
    ("time_in_contact", "D_STUCKTIME", float),
    ("segments", "D_SEGMENTS", int),
    ("search_steps", "D_STEPS", int),
    ("event_cap_reached", "D_CAP", bool),
    ("uncertified_peak_segments", "D_PEAK_GAVE_UP", int),
)


def read_diagnostics(diag, layout) -> dict:
    """The counters, the penetration and the energy balance of a kernel's diagnostics array."""
    out = {name: kind(diag[getattr(layout, index)])
           for name, index, kind in _DIAGNOSTIC_FIELDS if hasattr(layout, index)}
    out["max_penetration"] = float(max(diag[layout.D_PEN], 0.0))
    out.update(energy_balance(diag[layout.D_WORK], diag[layout.D_VISC], diag[layout.D_IMPLOSS],
                              diag[layout.D_FRICTION], diag[layout.D_E0], diag[layout.D_E1], diag[layout.D_EMAX]))
    return out
