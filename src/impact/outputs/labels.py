"""Words the study writes into its results and shows its readers: one place for each.

The study names its things by identifiers that are safe in a file name (``cid_mu0.01_e0.25``, ``s3_T1``,
``mu0.0252_d20_rp1_steel``, ``ivp_RK45``) and its tables' columns by identifiers (``within_10pct``).  A reader sees
words instead: :func:`label` turns any identifier the study makes into them, :func:`column_label` a table's
column, :func:`cell_text` a table's value.  The figures, both reports and the Snakemake report's subcategories
call these, so an identifier is spelled out in one place.
"""

from __future__ import annotations

import math
import re

from impact.model.kinds import KINDS
from impact.model.params import IMPACT_KINDS

#: the status of a numerics run its time budget stopped (``failed: too slow ...``), which the figures mark
TOO_SLOW = "too slow at this setting"

#: the meanings of the 0/1 flag every run records: whether it stopped at the engine's cap on events
EVENT_CAP_MEANINGS = ("finished", "stopped_at_event_cap")

#: what a stage that records scene runs (loads, ida) measures of each run, as (long name, units) of its variable
RUN_MEASURES = {
    "peak_accel": ("peak absolute roof acceleration", "m s-2"),
    "stroke": ("largest stroke of the damper mass relative to the roof", "m"),
    "impacts": ("number of impacts", "1"),
    "energy_residual": ("energy balance residual of the run, relative", "1"),
    "event_cap_reached": ("the run stopped at the engine's event cap", None),
}

DAMPERS = {**{name: name.upper() for name in KINDS}, "bare": "bare", "none": "bare"}

#: the measures the loads stage compares with the bare building
LOAD_MEASURES = {"peak_roof": "peak roof displacement", "rms_roof": "RMS roof displacement",
                 "peak_accel": "peak absolute roof acceleration", "peak_drift": "peak inter-storey drift"}

#: the numerics stage's methods and cases (stages/numerics/plan.py)
METHODS = {"core": "exact core", "rk4": "RK4, fixed step", "moreau_jean": "Moreau–Jean time stepping",
           "penalty": "penalty contact (Radau)"}
NUMERICS_CASES = {"cid_2eipc": "CID on its 2-EIPC orbit (g = 1.6, left start)",
                  "cid_irregular": "CID, irregular motion (e = 0.65, g = 0.5, r = 0.97)",
                  "pid_tuned": "PID tuned to the structure (r' = 1, g = 1)",
                  "cid_friction": "CID with friction (ν = 0.05, g = 1.6)"}

#: table columns whose name is not words with underscores
COLUMNS = {
    "within_10pct": "within 10 %", "rel_difference": "relative difference", "g_optimum": "g at the optimum",
    "refined_at_g_optimum": "refined X_m at that g", "grid_underestimate": "grid's underestimate",
    "X_m": "X_m", "mu": "μ", "beta": "β", "beta_t": "β_t", "nu": "ν", "rp": "r'", "e": "e", "r": "r",
    "sa_g": "Sa(T1) (g)", "mass_ratio": "mass ratio", "median_reduction": "median reduction",
    "reduction_low": "reduction, 5 %", "reduction_high": "reduction, 95 %", "share_lowered": "share helped",
    "share_raised": "share harmed", "theta_sa_g": "median capacity θ (g)", "drift_limit": "drift limit",
    "median_stroke_m": "median stroke (m)", "share_at_stroke_limit": "share at the stroke limit",
    "pga_g": "PGA (g)", "intensity": "PGA (g)", "intensity_g": "PGA (g)",
}

_NUMBER = r"-?[0-9.]+(?:e-?[0-9]+)?"
_WALLED = "|".join(IMPACT_KINDS)  # the damper kinds with walls, whose curves and designs the study names
_CURVE = re.compile(rf"^({_WALLED})_mu({_NUMBER})_e({_NUMBER})(?:_rp({_NUMBER}))?(?:_nu({_NUMBER}))?"
                    rf"(?:_f({_NUMBER}))?(?:_L({_NUMBER}))?$")
_BUILDING = re.compile(rf"^s(\d+)_T({_NUMBER})$")
_RIG_CASE = re.compile(rf"^mu({_NUMBER})_d({_NUMBER})_rp({_NUMBER})_(\w+)$")
_DESIGN = re.compile(rf"^({_WALLED})(?:_rp({_NUMBER}))?_(centre|left|right)$")
_IVP = re.compile(r"^ivp_(\w+)$")


def _curve(m) -> str:
    kind, mu, e, rp, nu, freq, unit = m.groups()
    parts = [f"{DAMPERS[kind]}, μ = {mu}, e = {e}"]
    if rp is not None:
        parts.append(f"r' = {rp}")
    if nu is not None:
        parts.append(f"ν = {nu}" + (f" ({freq} Hz" if freq else "") + (f", {float(unit) * 100:g} cm)" if unit else
                                                                         (")" if freq else "")))
    return ", ".join(parts)


def _building(m) -> str:
    storeys, period = int(m.group(1)), m.group(2)
    return f"{storeys} storey{'s' if storeys > 1 else ''}, T1 = {period} s"


def _rig_case(m) -> str:
    mu, gap, rp, wall = m.groups()
    return f"μ = {mu}, d = {gap} mm, r' = {rp}, {wall.replace('_', ' ')} wall"


def _design(m) -> str:
    kind, rp, start = m.groups()
    return f"{DAMPERS[kind]}" + (f" r' = {rp}" if rp else "") + f", {start} start"


_PATTERNS = ((_CURVE, _curve), (_BUILDING, _building), (_RIG_CASE, _rig_case), (_DESIGN, _design),
             (_IVP, lambda m: f"solve_ivp {m.group(1)}"))


def label(identifier) -> str:
    """Words for an identifier the study makes; anything else as it is."""
    text = str(identifier)
    for table in (DAMPERS, METHODS, NUMERICS_CASES, LOAD_MEASURES):
        if text in table:
            return table[text]
    for pattern, words in _PATTERNS:
        m = pattern.match(text)
        if m:
            return words(m)
    return text


def load_case(coordinates: dict) -> str:
    """One run of the loads stage in words, from its coordinates: its building, its load and its PGA."""
    words = {"building": label, "intensity": lambda v: f"PGA {float(v):g} g", "record": lambda v: f"record {v}",
             "seed": lambda v: f"seed {v}", "wind_seed": lambda v: f"wind seed {v}", "soil": lambda v: f"{v} soil"}
    return ", ".join(words.get(dim, lambda v, d=dim: f"{d} {v}")(value) for dim, value in coordinates.items())


def column_label(column: str) -> str:
    """A table column's header: its words, or its identifier with spaces for underscores."""
    return COLUMNS.get(column, column.replace("_", " "))


def cell_text(value) -> str:
    """A table value as a reader reads it: yes/no for booleans, a dash for a missing number, words for an
    identifier, numbers to four significant digits."""
    if isinstance(value, bool) or value in ("True", "False"):
        return "yes" if value in (True, "True") else "no"
    if value is None or value == "" or (isinstance(value, float) and math.isnan(value)) or value in ("nan", "NaN"):
        return "–"
    if isinstance(value, (int, float)):
        return f"{value:.4g}"
    return label(value)
