"""Table 1 of the paper in numbers, from the designs' datasets (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from impact.model.kinds import CID, KINDS, PID, TMD
from impact.stages.robustness.designs import (
    BAND,
    SAME_LEVEL,
)


def within_band(x, xm, design_value: float, at: float, band: float = BAND) -> tuple[float, float]:
    """The contiguous range of x around ``at`` over which X_m stays within ``band`` of its design value.

    Returns the grid's end points of that range (a range that reaches the grid's end is open there).
    """
    x, ok = np.asarray(x, dtype=float), np.abs(np.asarray(xm, dtype=float) / design_value - 1.0) <= band
    i = int(np.argmin(np.abs(x - at)))
    if not ok[i]:
        return math.nan, math.nan
    lo = hi = i
    while lo > 0 and ok[lo - 1]:
        lo -= 1
    while hi + 1 < x.size and ok[hi + 1]:
        hi += 1
    return float(x[lo]), float(x[hi])


def max_change(ds, name: str) -> float:
    """The largest relative change of X_m from its design value along one variation (NaN: not varied)."""
    key = f"X_m_vs_{name}"
    if key not in ds:
        return math.nan
    return float(np.max(np.abs(ds[key].values / float(ds["X_m_design"]) - 1.0)))


# Table 1 of the paper: its row, characteristic and words for the CID, PID and TMD ("not rated": its "~ . ~")
#: the kinds of the paper's Table 1, in the order of its columns (each row's words below)
TABLE1_COLUMNS = (CID, PID, TMD)
TABLE1 = [
    (2, "effectiveness for steady-state motion", ("moderate", "moderate", "high")),
    (5, "space requirement", ("moderate", "moderate", "high")),
    (6, "sensitivity to tuning", ("not rated", "low", "high")),
    (7, "sensitivity to damping of the damper", ("not rated", "not rated", "high")),
    (9, "sensitivity to amplitude of the excitation", ("high", "moderate", "low")),
    (10, "material dependence (coefficient of restitution)", ("moderate", "moderate", "moderate")),
]


WORD_RANK = {"low": 0, "moderate": 1, "high": 2}


_NUMBERS = {
    2: ("1 / X_m at the design point", lambda ds: 1.0 / float(ds["X_m_design"])),
    5: ("largest stroke over A_max", lambda ds: float(ds["stroke_max_design"]) / float(ds.attrs["a_max"])),
    6: ("largest relative change of X_m over the drifts", lambda ds: max_change(ds, "drift")),
    7: ("largest relative change of X_m over the damping ratios", lambda ds: max_change(ds, "damping")),
    9: ("largest relative change of X_m over the force scales", lambda ds: max_change(ds, "scale")),
    10: ("largest relative change of X_m over e", lambda ds: max_change(ds, "e")),
}


def _supports(rank: int | None, number: float, others: list[tuple[int | None, float]]) -> str:
    """Does the number order like the word against every other damper's (higher word, larger number)?"""
    if rank is None or not math.isfinite(number):
        return "not judged"
    ordered = [(r, n) for r, n in others if r is not None and math.isfinite(n) and r != rank]
    if not ordered:
        return "not judged"
    ok = all((n < number) if r < rank else (n > number) for r, n in ordered)
    return "yes" if ok else "no"


def table1_measured(designs: dict) -> pd.DataFrame:
    """One row per Table 1 characteristic we compute and per design: the paper's word, our number, support.

    designs: design name -> its dataset.  A number 'supports' the word when it orders against every other
    damper's number as the words order (low < moderate < high; a larger number is more of the
    characteristic; effectiveness is 1/X_m), for every design of a damper with a different word.
    """
    column = {kind: i for i, kind in enumerate(TABLE1_COLUMNS)}
    rows = []
    for row, characteristic, words in TABLE1:
        what, number = _NUMBERS[row]
        entries = []
        for name, ds in designs.items():
            word = words[column[ds.attrs["kind"]]]
            entries.append((name, ds.attrs["kind"], word, WORD_RANK.get(word), number(ds)))
        for name, kind, word, rank, value in entries:
            others = [(r, v) for n, k, _, r, v in entries if k != kind]
            ds = designs[name]
            lo, hi = _band(ds, row)
            rows.append({"row": row, "characteristic": characteristic, "design": name, "damper": kind.upper(),
                         "paper_word": word, "measure": what, "number": value,
                         "supports": _supports(rank, value, others), "band_lo": lo, "band_hi": hi,
                         "note": _note(ds, row)})
    rows += [_multi_unit_row(name, ds) for name, ds in designs.items() if "X_m_units_symmetric" in ds]
    return pd.DataFrame(rows)


def _multi_unit_row(name: str, ds) -> dict:
    change, holds = same_level(ds)
    n = ds["units"].values
    return {"row": 5, "characteristic": f"space: {n.max()} units instead of one (Ref. 14: up to 9 units give "
            "the same level of performance)", "design": name, "damper": ds.attrs["kind"].upper(),
            "paper_word": "same level", "measure": "largest relative change of X_m from one unit, each start "
            f"(same, staggered, ensemble median) against its own one-unit value, n = {', '.join(map(str, n))}",
            "number": change, "supports": {True: "yes", False: "no", None: "not judged"}[holds],
            "band_lo": math.nan, "band_hi": math.nan,
            "note": _multi_unit_note(ds, holds)}


def _multi_unit_note(ds, holds: bool | None) -> str:
    undefined = [int(n) for n, ok in zip(ds["units"].values, _all_defined(ds)) if not ok]
    if not undefined:
        return f"'same level' read as within {SAME_LEVEL:.0%}"
    capped = (f"X_m undefined for n = {', '.join(map(str, undefined))}: a run of the split damper stopped at "
              "the event cap (the units' grazing contacts accumulate)")
    if holds is False:
        return f"{capped}; the defined n already move X_m beyond {SAME_LEVEL:.0%}, which refutes the claim"
    return f"{capped}, so the claim is not judged"


def _all_defined(ds) -> np.ndarray:
    """Per number of units: whether every X_m of it (together, staggered, every ensemble member) is defined."""
    return (np.isfinite(ds["X_m_units_symmetric"].values) & np.isfinite(ds["X_m_units_staggered"].values)
            & np.all(np.isfinite(ds["X_m_units_ensemble"].values), axis=1))


def _band(ds, row: int) -> tuple[float, float]:
    """Rows 6 and 9: the range of drift or scale over which X_m stays within 25 % of its design value."""
    name, at = {6: ("drift", 0.0), 9: ("scale", 1.0)}.get(row, (None, None))
    if name is None or f"X_m_vs_{name}" not in ds:
        return math.nan, math.nan
    return within_band(ds[name].values, ds[f"X_m_vs_{name}"].values, float(ds["X_m_design"]), at)


def _note(ds, row: int) -> str:
    kind = ds.attrs["kind"]
    if row == 7 and not KINDS[kind].dashpot:
        return (f"a CID has no damper damping; its dissipation is set by e instead, and X_m changes by up to "
                f"{max_change(ds, 'e'):.0%} over e = 0 to 1 (row 10)")
    if row == 5 and "X_m_capped" in ds:
        return (f"stroke capped to the CID's half gap {float(ds['stroke_cap']):.3g}: beta_t "
                f"{float(ds['damping_capped']):.3g}, X_m {float(ds['X_m_capped']):.3f} (uncapped "
                f"{float(ds['X_m_design']):.3f})")
    if row == 5 and KINDS[kind].walls:
        return "bounded by half the gap: the mass travels between the walls"
    if row == 10 and not KINDS[kind].walls:
        return "a TMD has no impacts: nothing in it depends on e"
    return ""


def same_level(ds) -> tuple[float, bool | None]:
    """The largest relative change of X_m from one unit to n, each kind of start against its own single-unit
    value (the ensemble by its median), and whether it stays within SAME_LEVEL.

    Where some X_m is undefined (a run of the split damper stopped at the event cap), the claim is still
    refuted by any defined change beyond SAME_LEVEL (it is a claim about every n up to 9); otherwise the
    verdict is withheld: (largest defined change or NaN, None).
    """
    curves = [ds["X_m_units_symmetric"].values, ds["X_m_units_staggered"].values,
              np.median(ds["X_m_units_ensemble"].values, axis=1)]
    one = list(ds["units"].values).index(1)
    changes = np.concatenate([np.abs(c / c[one] - 1.0) for c in curves])
    defined = changes[np.isfinite(changes)]
    change = float(np.max(defined)) if defined.size else math.nan
    if defined.size < changes.size:
        return (change, False) if change > SAME_LEVEL else (change, None)
    return change, change <= SAME_LEVEL
