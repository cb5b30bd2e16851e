"""The paper's reported values (model.md, "Reported values") beside ours.

Each reported value names the curve it comes from; a row is produced only
when the study's configuration contains that curve.  Where ours differ from
the paper by more than 10 %, the row says why as far as the data can tell:
the initial place of the damper mass, the edge of the gap grid, or neither.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from impact.model.kinds import CID, PID
from impact.model.params import curve_id
from impact.outputs.datasets import optimum, two_ipc_range

TOLERANCE = 0.10


def _cid(mu, e):
    return {"damper": CID, "mu": mu, "e": e}


def _pid(mu, e, rp):
    return {"damper": PID, "mu": mu, "e": e, "rp": rp}


# (figure, case, curve spec, quantity, paper value)
X_M_AT_OPTIMUM = [
    ("8(a), 9(a)", "CID mu=0.01 e=0.25", _cid(0.01, 0.25), 0.32),
    ("9(a)", "CID mu=0.01 e=0.45", _cid(0.01, 0.45), 0.22),
    ("9(a)", "CID mu=0.01 e=0.65", _cid(0.01, 0.65), 0.40),
    ("8(b)", "PID mu=0.01 e=0.25 r'=0.5", _pid(0.01, 0.25, 0.5), 0.42),
    ("8(c)", "PID mu=0.01 e=0.25 r'=1.0", _pid(0.01, 0.25, 1.0), 0.50),
    ("8(d)", "PID mu=0.01 e=0.25 r'=1.5", _pid(0.01, 0.25, 1.5), 0.80),
]
TWO_IPC_RANGES = [
    ("8(b)", "PID mu=0.01 e=0.25 r'=0.5", _pid(0.01, 0.25, 0.5), (0.8, 1.2)),
    ("8(c)", "PID mu=0.01 e=0.25 r'=1.0", _pid(0.01, 0.25, 1.0), (0.8, 4.4)),
    ("8(d)", "PID mu=0.01 e=0.25 r'=1.5", _pid(0.01, 0.25, 1.5), (0.6, 1.0)),
    ("8(c)", "PID mu=0.03 e=0.25 r'=1.0", _pid(0.03, 0.25, 1.0), (0.4, 1.6)),
]
E_TREND_PID = [(rp, [_pid(0.01, e, rp) for e in (0.25, 0.45, 0.65)]) for rp in (0.5, 1.0, 1.5)]
TMD_PAPER = {"f": 0.99, "beta_t": 0.06}
FRICTION = [{"damper": CID, "mu": 0.01, "e": 0.25, **({"nu": nu} if nu else {})} for nu in (0.0, 0.05, 0.2, 0.5)]


def needed_curves() -> list:
    """Specs of every curve a reported value refers to."""
    specs = [row[2] for row in X_M_AT_OPTIMUM + TWO_IPC_RANGES]
    for _, group in E_TREND_PID:
        specs.extend(group)
    return specs + FRICTION


def _rel(ours, paper):
    return (ours - paper) / abs(paper) if math.isfinite(ours) else math.nan


def _row(figure, case, quantity, start, paper, ours, reason=""):
    diff = _rel(ours, paper)
    agrees = bool(math.isfinite(diff) and abs(diff) <= TOLERANCE)
    return {"figure": figure, "case": case, "quantity": quantity, "start": start, "paper": paper,
            "reproduced": ours, "rel_difference": diff, "within_10pct": agrees,
            "reason": "" if agrees else reason}


def _xm_reason(ds, start, g_opt, others):
    gaps = ds["gap_ratio"].values
    bits = []
    matching = [f"start '{s}' gives {v:.3f}" for s, v in others if math.isfinite(v)]
    if g_opt in (gaps.min(), gaps.max()):
        bits.append(f"optimum at the edge of the gap grid (g={g_opt:g})")
    if matching:
        bits.append("initial condition matters: " + "; ".join(matching))
    return "; ".join(bits) or "not explained by the start or the grid (nor by the sweep modes and readings of coexistence_e_trend.json)"


def x_m_rows(datasets: dict) -> list:
    rows = []
    for figure, case, spec, paper in X_M_AT_OPTIMUM:
        ds = datasets.get(curve_id(spec))
        if ds is None:
            continue
        starts = [str(s) for s in ds["start"].values]
        best = {s: optimum(ds, s) for s in starts}
        for s in starts:
            g_opt, xm = best[s]
            others = [(o, best[o][1]) for o in starts if o != s and abs(_rel(best[o][1], paper)) <= TOLERANCE]
            refined = float(ds["X_m_refined"].sel(start=s, gap_ratio=g_opt)) if math.isfinite(g_opt) else math.nan
            rows.append(_row(figure, case, "X_m at optimum g", s, paper, xm, _xm_reason(ds, s, g_opt, others))
                        | {"g_optimum": g_opt, "refined_at_g_optimum": refined,
                           "grid_underestimate": (refined - xm) / refined})
    return rows


def closed_form_at_simulated_optimum_rows(datasets: dict) -> list:
    """A reading of the paper's CID e-trend: the stable 2-EIPC closed form's X_m at the gap where the simulation
    has its optimum (not at the closed form's own optimum), per start, beside the paper's value."""
    rows = []
    for figure, case, spec, paper in X_M_AT_OPTIMUM:
        ds = datasets.get(curve_id(spec))
        if ds is None or "X_m_closed_form" not in ds:
            continue
        for s in [str(x) for x in ds["start"].values]:
            g_opt, _ = optimum(ds, s)
            xm = float(ds["X_m_closed_form"].sel(gap_ratio=g_opt)) if math.isfinite(g_opt) else math.nan
            reason = ("no stable 2-EIPC orbit at that gap on the frequency grid" if not math.isfinite(xm)
                      else "the closed form at the simulation's optimum gap does not give the paper's value")
            rows.append(_row(figure, case, "X_m of the 2-EIPC closed form at the simulated optimum g", s, paper, xm,
                             reason) | {"g_optimum": g_opt})
    return rows


def two_ipc_rows(datasets: dict) -> list:
    rows = []
    for figure, case, spec, (lo, hi) in TWO_IPC_RANGES:
        ds = datasets.get(curve_id(spec))
        if ds is None:
            continue
        for s in [str(x) for x in ds["start"].values]:
            ours_lo, ours_hi = two_ipc_range(ds, s)
            for end, paper, ours in (("lower", lo, ours_lo), ("upper", hi, ours_hi)):
                reason = ("no 2 IPC at x_max anywhere on the grid" if not math.isfinite(ours)
                          else f"our 2-IPC range is {ours_lo:g}-{ours_hi:g} (classified at the frequency of x_max)")
                rows.append(_row(figure, case, f"2-IPC range, {end} g", s, paper, ours, reason))
    return rows


def e_trend_rows(datasets: dict) -> list:
    rows = []
    for rp, group in E_TREND_PID:
        dss = [datasets.get(curve_id(spec)) for spec in group]
        if any(ds is None for ds in dss):
            continue
        for s in [str(x) for x in dss[0]["start"].values]:
            xms = [optimum(ds, s)[1] for ds in dss]
            monotone = bool(np.all(np.diff(xms) > 0))
            rows.append({"figure": "9(b-d)", "case": f"PID mu=0.01 r'={rp:g}, e=0.25/0.45/0.65",
                         "quantity": "X_m at optimum rises with e", "start": s, "paper": "yes",
                         "reproduced": "yes" if monotone else "no (" + "/".join(f"{x:.3f}" for x in xms) + ")",
                         "rel_difference": math.nan, "within_10pct": monotone,
                         "reason": "" if monotone else "X_m at optimum is not monotone in e"})
    return rows


def friction_rows(datasets: dict) -> list:
    """Fig. 10: friction lowers the CID's efficiency (X_m at optimum rises with nu), default scale."""
    dss = [datasets.get(curve_id(spec)) for spec in FRICTION]
    if any(ds is None for ds in dss):
        return []
    rows = []
    for s in [str(x) for x in dss[0]["start"].values]:
        xms = [optimum(ds, s)[1] for ds in dss]
        rises = bool(np.all(np.diff(xms) >= 0) and xms[-1] > xms[0])
        rows.append({"figure": "10", "case": "CID mu=0.01 e=0.25, nu=0/0.05/0.2/0.5 (1.5 Hz, 1 cm)",
                     "quantity": "friction lowers efficiency (X_m at optimum rises with nu)", "start": s,
                     "paper": "yes", "reproduced": ("yes" if rises else "no") + " (" +
                     "/".join(f"{x:.3f}" for x in xms) + ")", "rel_difference": math.nan,
                     "within_10pct": rises, "reason": "" if rises else "X_m at optimum is not monotone in nu"})
    return rows


def tmd_rows(tmd: dict | None, datasets: dict) -> list:
    if tmd is None:
        return []
    rows = [_row("11", "TMD mu=0.01 beta=0.0048", f"optimum {k}", "-", TMD_PAPER[k], tmd[k],
                 "the paper quotes two digits" if k == "beta_t" else "") for k in ("f", "beta_t")]
    cid = datasets.get(curve_id(_cid(0.01, 0.25)))
    pids = [datasets.get(curve_id(_pid(0.01, 0.25, rp))) for rp in (0.5, 1.0, 1.5)]
    if cid is not None and all(ds is not None for ds in pids):
        for s in [str(x) for x in cid["start"].values]:
            xm_cid = optimum(cid, s)[1]
            xm_pid = min(optimum(ds, str(ds["start"].values[0]))[1] for ds in pids)
            order = tmd["X_m"] < xm_cid < xm_pid
            rows.append({"figure": "11", "case": "efficiency order", "quantity": "TMD > CID > PID",
                         "start": s, "paper": "yes",
                         "reproduced": f"{'yes' if order else 'no'} (X_m TMD {tmd['X_m']:.3f}, CID {xm_cid:.3f}, "
                                       f"best PID {xm_pid:.3f})",
                         "rel_difference": math.nan, "within_10pct": bool(order),
                         "reason": "" if order else "order differs for this start"})
    return rows


def paper_vs_reproduced(datasets: dict, tmd: dict | None) -> pd.DataFrame:
    rows = (x_m_rows(datasets) + closed_form_at_simulated_optimum_rows(datasets) + two_ipc_rows(datasets)
            + e_trend_rows(datasets) + friction_rows(datasets) + tmd_rows(tmd, datasets))
    cols = ["figure", "case", "quantity", "start", "paper", "reproduced", "rel_difference", "within_10pct",
            "g_optimum", "refined_at_g_optimum", "grid_underestimate", "reason"]
    return pd.DataFrame(rows, columns=cols)


# --- coexisting steady states (continuation, ensemble) beside the paper ------------------------

def coexistence_table(paper: dict, from_rest: dict, continuation: dict, ensembles: dict) -> pd.DataFrame:
    """Per CID curve: X_m at the optimum gap for every mode and start, the envelope, the best match.

    paper: curve id -> the paper's X_m; from_rest / ensembles: id -> dataset;
    continuation: (id, mode) -> dataset.
    """
    rows = []
    for cid, ds_rest in from_rest.items():
        candidates = {}
        for start in ds_rest["start"].values:
            candidates[f"from_rest, start {start}"] = optimum(ds_rest, str(start))
        # the paper's possible reading: Masri's closed form where a stable 2-EIPC orbit exists
        if "X_m_closed_form" in ds_rest:
            candidates["closed form alone"] = optimum(ds_rest, None, "X_m_closed_form")
            for start in ds_rest["start"].values:
                candidates[f"hybrid (closed form, else from_rest), start {start}"] = optimum(
                    ds_rest, str(start), "X_m_hybrid")
        for (cid2, mode), ds in continuation.items():
            if cid2 == cid:
                for start in ds["start"].values:
                    candidates[f"{mode}, start {start}"] = optimum(ds, str(start))
        ens = ensembles.get(cid)
        row = {"curve": cid, "paper_X_m": paper.get(cid, math.nan)}
        for name, (g, xm) in candidates.items():
            row[f"X_m [{name}]"] = xm
            row[f"g [{name}]"] = g
        if ens is not None:
            for stat in ("min", "median", "max"):
                vals = ens[f"X_m_{stat}"].values
                i = int(np.nanargmin(vals))
                row[f"envelope {stat}: X_m at its optimum"] = float(vals[i])
                row[f"envelope {stat}: g"] = float(ens["gap_ratio"].values[i])
            row["most attractors at one (g, r)"] = int(ens["attractors"].max())
        target = row["paper_X_m"]
        if math.isfinite(target):
            best = min(candidates.items(), key=lambda kv: abs(kv[1][1] - target))
            row["closest to the paper"] = best[0]
            row["closest X_m"] = best[1][1]
            row["closest rel. difference"] = (best[1][1] - target) / target
            if ens is not None:
                row["paper within ensemble range"] = bool(
                    np.nanmin(ens["X_m_min"].values) <= target <= np.nanmin(ens["X_m_max"].values))
        rows.append(row)
    return pd.DataFrame(rows)


def e_trend_statement(table: pd.DataFrame, e_of: dict) -> str:
    """Does any mode, start or the envelope give the paper's e-trend (X_m lowest at e = 0.45)?"""
    curves = sorted((e_of[c], c) for c in table["curve"] if c in e_of)
    if len(curves) < 3:
        return "not enough restitution values in the study to judge the e-trend"
    cols = [c for c in table.columns if c.startswith("X_m [") or (c.startswith("envelope") and c.endswith("optimum"))]
    paper = [float(table.loc[table["curve"] == cid, "paper_X_m"].iloc[0]) for _, cid in curves]
    found = []
    all_close = False
    for col in cols:
        vals = [float(table.loc[table["curve"] == cid, col].iloc[0]) for _, cid in curves]
        if all(math.isfinite(v) for v in vals) and int(np.argmin(vals)) == 1:
            name = col[len("X_m ["):-1] if col.startswith("X_m [") else col.replace(": X_m at its optimum", "")
            close = sum(abs(v - q) <= 0.1 * q for v, q in zip(vals, paper) if math.isfinite(q))
            found.append(f"{name}: " + "/".join(f"{v:.3f}" for v in vals) + f" ({close} of 3 within 10 % of the paper)")
            all_close = all_close or close == len(vals)
    es = "/".join(f"{e:g}" for e, _ in curves)
    if found:
        quoted = "/".join(f"{q:.2f}" for q in paper)
        verdict = ("One of them also matches the paper's values within 10 %." if all_close else
                   "None of them matches all three of the paper's values within 10 %: the minimum is where the "
                   "paper has it, but the dip's depth is not explained by the sweep protocol or the start.")
        return (f"X_m at the optimum gap is lowest at the middle e (e = {es}; paper {quoted}), as the paper says, "
                "for: " + "; ".join(found) + ". " + verdict)
    return (f"No sweep mode, start or ensemble statistic gives X_m lowest at the middle e (e = {es}): "
            "the paper's e-trend is not explained by the initial condition or the sweep protocol here")


def closed_form_statement(table: pd.DataFrame, e_of: dict) -> str:
    """Does reading X_m from Masri's closed form, where a stable 2-EIPC orbit exists, give the paper's e-trend?"""
    curves = sorted((e_of[c], c) for c in table["curve"] if c in e_of)
    readings = [c[len("X_m ["):-1] for c in table.columns
                if c.startswith("X_m [") and ("closed form" in c or "hybrid" in c)]
    if len(curves) < 3 or not readings:
        return "no closed-form reading in the study (it needs three frictionless CID curves of different e)"

    def values(reading, key="X_m"):
        return [float(table.loc[table["curve"] == cid, f"{key} [{reading}]"].iloc[0]) for _, cid in curves]

    paper = [float(table.loc[table["curve"] == cid, "paper_X_m"].iloc[0]) for _, cid in curves]
    parts, explains = [], []
    for reading in readings:
        xm, g = values(reading), values(reading, "g")
        parts.append(f"{reading}: " + "/".join(f"{v:.3f} (g = {gi:g})" for v, gi in zip(xm, g)))
        if all(math.isfinite(v) and abs(v - q) <= TOLERANCE * q for v, q in zip(xm, paper)):
            explains.append(reading)
    verdict = (f"This reading explains the paper's values ({'; '.join(explains)})." if explains else
               "No closed-form reading gives all three of the paper's values within 10 %: reading x_max from the "
               "closed form where it exists does not explain the paper's e-trend.")
    return (f"X_m at the optimum gap read from Masri's closed form (e = {'/'.join(f'{e:g}' for e, _ in curves)}; "
            f"paper {'/'.join(f'{q:.2f}' for q in paper)}): " + "; ".join(parts) + ". " + verdict)
