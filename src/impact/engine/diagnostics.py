"""A run's diagnostics array as named numbers: counters, penetration and the energy balance.

Both loops of the engine write their diagnostics into a float64 vector whose indices layout.py names;
:func:`read_diagnostics` turns it into a dict with the same keys for either.
"""

from __future__ import annotations

from impact.engine import layout as L


def energy_balance(work: float, viscous: float, impact_losses: float, friction: float, e0: float, e1: float,
                   e_max: float, plastic: float = 0.0) -> dict:
    """A run's energy terms and the residual of its balance, work - losses - (E1 - E0).

    The residual is normalised by the largest energy in play (the work, the losses or the most the run
    stored), so that a run that stores far more than it exchanges (no damping, a mass started at a far
    wall) is judged on the right scale.  plastic: a yielding building's plastic work, a loss like the others
    (its own measure is StoreyResponse.plastic_work, so an elastic run's keys are what they were).
    """
    losses = viscous + impact_losses + friction + plastic
    residual = work - losses - (e1 - e0)
    scale = max(abs(work), losses, e_max, 1e-300)
    return {"energy_residual": float(residual / scale), "work_input": float(work),
            "viscous_dissipation": float(viscous), "impact_losses": float(impact_losses),
            "friction_work": float(friction)}


# A loop's diagnostics as named numbers: the name, its index in the layout, the type
_DIAGNOSTIC_FIELDS = (
    ("impacts", L.D_IMPACTS, int),
    ("impacts_in_window", L.D_IMPACTS_WIN, int),
    ("simultaneous_impact_events", L.D_SIMULTANEOUS, int),
    ("sticking_episodes", L.D_STICKS, int),
    ("grazing_events", L.D_GRAZE, int),
    ("time_in_contact", L.D_STUCKTIME, float),
    ("segments", L.D_SEGMENTS, int),
    ("clear_steps", L.D_CLEAR, int),
    ("search_steps", L.D_STEPS, int),
    ("event_cap_reached", L.D_CAP, bool),
    ("uncertified_peak_segments", L.D_PEAK_GAVE_UP, int),
)


STOPPED_BY = {0: "", L.STOP_CAP: "event cap", L.STOP_STALL: "stall guard", L.STOP_BUDGET: "event budget"}


def stop(diag) -> dict:
    """Why a run stopped early ("" if it did not) and at which element's event: its unit (the index of the
    impact records' unit column, damper by damper) or its storey (1 at the ground), the event's kind and side."""
    by = STOPPED_BY[int(diag[L.D_CAP])]
    element = int(diag[L.D_STOP_ELEMENT])
    event = int(diag[L.D_STOP_EVENT])
    storey = event in (L.EV_YIELD, L.EV_UNLOAD, L.EV_COLLAPSE)
    return {"stopped_by": by, "stop_event": L.EVENT_NAMES[event] if by else "",
            "stop_side": int(diag[L.D_STOP_SIDE]) if by else 0,
            "stop_unit": element if by and not storey else -1, "stop_storey": element + 1 if by and storey else -1}


#: the energy balance's terms in a run's diagnostics (energy_balance), and the deepest penetration (with the part
#: of it beyond the round-off of the positions it was read from, contact.note_penetration)
ENERGY_TERMS = ("energy_residual", "work_input", "viscous_dissipation", "impact_losses", "friction_work",
                "max_penetration", "penetration_beyond_roundoff")


def read_diagnostics(diag) -> dict:
    """The counters, the penetration and the energy balance of a loop's diagnostics array, and why it stopped."""
    out = {name: kind(diag[index]) for name, index, kind in _DIAGNOSTIC_FIELDS}
    out.update(stop(diag))
    out["max_penetration"] = float(max(diag[L.D_PEN], 0.0))
    out["penetration_beyond_roundoff"] = float(max(diag[L.D_PEN_EXCESS], 0.0))
    out.update(energy_balance(diag[L.D_WORK], diag[L.D_VISC], diag[L.D_IMPLOSS], diag[L.D_FRICTION],
                              diag[L.D_E0], diag[L.D_E1], diag[L.D_EMAX], diag[L.D_PLASTIC]))
    return out
