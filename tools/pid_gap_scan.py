"""Why the PID has no design equation: its optimum gap on a fine grid, and how well a gap law can find it.

The design charts read X_m on the protocol's gap grid (0.2 apart).  This script scans PID designs on that grid and
then, between the grid optimum's two neighbours, on the design equations' fine step (design.equations.refine_step,
0.01; formulas.refined_curve), with the charts' frequency window and protocol (the worst over the starts, as `impact design` reads it).  It reports, per design, the grid's
optimum against the fine one, and the cliff the fine scan finds below the optimum: X_m just below the optimum gap
over X_m at it.  Then it fits a gap law to the fine optima of the rows of e that the design equations fit
(design.equations.holdout_e held out),

    1 / g_opt = B (1 - r'^2)^w + A (mu / beta)^p (1 - e)^s (1 - r'^2)^q

(the impacts' share of the energy balance grows as mu / beta, their momentum as 1 - e; 1 - r'^2 is how much a
soft pendulum lags the structure), and X_m above the optimum by a power of the gap, and says how far from the
optimum the law's gap lands on the held-out rows: a gap below the cliff, or one whose X_m is more than the
configured plateau above the optimum, fails the design equations' check.

    python -m impact.kernels tools/pid_gap_scan.py --out docs/pid_gap_scan.json   # about 10 min
    python -m impact.kernels tools/pid_gap_scan.py --rows docs/pid_gap_scan.json  # the fit again, no scans
"""

from __future__ import annotations

import argparse
import itertools
import json
import time
from pathlib import Path

import numpy as np
import yaml
from scipy.optimize import least_squares

from impact.stages.design.equations.formulas import Point, direct_xm, refined_curve
from impact.stages.sweeps import gap_grid

CONFIG = Path(__file__).resolve().parents[1] / "config" / "config.yaml"


def scan(cfg: dict, pt: Point) -> dict:
    """The grid's optimum, then the refined curve around it (formulas.refined_curve, the design equations' own)."""
    coarse = gap_grid(cfg)
    xc = direct_xm(cfg, "pid", pt, coarse)
    i = int(np.nanargmin(xc))
    gaps, xm = refined_curve(cfg, "pid", pt, coarse, xc)
    window = (gaps >= coarse[max(i - 1, 0)]) & (gaps <= coarse[min(i + 1, len(coarse) - 1)])
    fine, xf = gaps[window], np.round(xm[window], 6)  # what the output file keeps, so a refit of it is the same
    j = int(np.nanargmin(xf))
    return {"mu": pt.mu, "e": pt.e, "beta": pt.beta, "rp": pt.rp,
            "grid_gap": float(coarse[i]), "grid_X_m": float(np.round(xc[i], 6)), "gap": float(fine[j]),
            "X_m": float(xf[j]), "cliff": float(xf[j - 1] / xf[j]) if j > 0 else None,
            "fine_gaps": fine.tolist(), "fine_X_m": xf.tolist()}


def gap_law(c, mu, e, rp, beta):
    b, a, p, s, q, w = c
    soft = 1.0 - rp ** 2
    return 1.0 / (b * soft ** w + a * (mu / beta) ** p * (1.0 - e) ** s * soft ** q)


def fit_gap_law(rows: list[dict]) -> np.ndarray:
    mu, e, rp, beta, gap = (np.array([r[k] for r in rows]) for k in ("mu", "e", "rp", "beta", "gap"))
    return least_squares(lambda c: np.log(gap_law(c, mu, e, rp, beta) / gap), [0.4, 0.2, 1.0, 0.3, 0.0, 0.5]).x


def branch_exponent(rows: list[dict]) -> float:
    """X_m above the optimum ~ g^k, fitted on the fine scans' points from the optimum to one grid step above it."""
    logs = []
    for r in rows:
        g, x = np.array(r["fine_gaps"]), np.array(r["fine_X_m"])
        above = g >= r["gap"]
        logs += [(np.log(gg / r["gap"]), np.log(xx / r["X_m"])) for gg, xx in zip(g[above], x[above]) if gg > r["gap"]]
    dg, dx = np.array(logs).T
    return float(dg @ dx / (dg @ dg))


def landing(rows: list[dict], coefs, margin: float) -> list[dict]:
    """Where the law's gap, raised by `margin`, lands on each row's fine scan: X_m there over the optimum."""
    out = []
    for r in rows:
        g = gap_law(coefs, r["mu"], r["e"], r["rp"], r["beta"]) * (1.0 + margin)
        gaps, xm = np.array(r["fine_gaps"]), np.array(r["fine_X_m"])
        inside = gaps[0] <= g <= gaps[-1]
        x = float(np.interp(g, gaps, xm)) if inside else None
        out.append({"mu": r["mu"], "e": r["e"], "rp": r["rp"], "gap_law": g, "gap": r["gap"],
                    "over_optimum": x / r["X_m"] - 1.0 if x is not None else None, "below_cliff": bool(g < r["gap"])})
    return out


def _range(values) -> list[float]:
    values = [float(v) for v in values]
    return [min(values), max(values)]


def summarise(rows: list[dict], eq: dict, soft_max: float) -> tuple[dict, list[dict]]:
    """The gap law fitted on the soft pendulums' rows of e not held out, and how it lands on the held-out ones."""
    soft = [r for r in rows if r["rp"] <= soft_max]
    held = set(eq["holdout_e"])
    train = [r for r in soft if r["e"] not in held]
    test = [r for r in soft if r["e"] in held]
    coefs = fit_gap_law(train)
    k = branch_exponent(soft)

    def errors(group):
        return _range(gap_law(coefs, r["mu"], r["e"], r["rp"], r["beta"]) / r["gap"] - 1.0 for r in group)

    # the band a gap may land in: at or above the optimum (below it is the cliff), and X_m within the plateau
    band = (1.0 + eq["plateau"]) ** (1.0 / k) - 1.0
    fitted = errors(train)
    margin = -fitted[0]  # the law's gap raised by its worst under-estimate on the fitted designs
    lands = landing(test, coefs, margin)
    worst_cliff = max((r for r in soft if r["cliff"]), key=lambda r: r["cliff"])
    worst_grid = max(soft, key=lambda r: r["grid_X_m"] / r["X_m"])
    return {"designs": len(rows), "soft_designs": len(soft), "soft_max_rp": soft_max,
            "best_X_m_soft": _range(r["X_m"] for r in soft),
            "best_X_m_stiffer": _range(r["X_m"] for r in rows if r["rp"] > soft_max) if len(soft) < len(rows) else None,
            "grid_over_fine_max": worst_grid["grid_X_m"] / worst_grid["X_m"] - 1.0,
            "grid_over_fine_worst": {k_: worst_grid[k_] for k_ in ("mu", "e", "rp", "grid_gap", "grid_X_m", "gap", "X_m")},
            "cliff_max": worst_cliff["cliff"],
            "cliff_worst": {k_: worst_cliff[k_] for k_ in ("mu", "e", "rp", "gap", "X_m")},
            "gap_law": dict(zip("B A p s q w".split(), map(float, coefs))),
            "gap_error_fitted": fitted, "gap_error_held_out": errors(test),
            "branch_exponent": k, "band_above_optimum": band, "margin": margin,
            "held_out": len(lands),
            "held_out_within_plateau": sum(1 for x in lands if not x["below_cliff"]
                                           and x["over_optimum"] is not None and x["over_optimum"] <= eq["plateau"]),
            "held_out_beyond_plateau": sum(1 for x in lands if x["over_optimum"] is not None
                                           and x["over_optimum"] > eq["plateau"]),
            "held_out_at_or_below_edge": sum(1 for x in lands if x["below_cliff"]),
            "held_out_over_optimum_max": max(x["over_optimum"] for x in lands if x["over_optimum"] is not None)}, lands


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rp", type=float, nargs="+", default=[0.5, 0.6, 0.7, 0.8, 1.0, 1.25, 1.5])
    ap.add_argument("--soft-max", type=float, default=0.8, help="the largest r' the gap law is fitted on")
    ap.add_argument("--out", default="pid_gap_scan.json")
    ap.add_argument("--rows", help="the scans of an earlier --out, fitted again without scanning")
    args = ap.parse_args()
    cfg = yaml.safe_load(CONFIG.read_text())
    design = cfg["design"]
    beta = cfg["structure"]["beta"]
    rows, start = json.loads(Path(args.rows).read_text())["rows"] if args.rows else [], time.perf_counter()
    for rp, mu, e in [] if args.rows else itertools.product(args.rp, design["mu"], design["e"]):
        rows.append(scan(cfg, Point(mu, e, beta, rp)))
        r = rows[-1]
        print(f"r' {rp} mu {mu} e {e}: grid g {r['grid_gap']:.2f} X_m {r['grid_X_m']:.4f}; fine g {r['gap']:.2f} "
              f"X_m {r['X_m']:.4f}; cliff x{r['cliff'] or float('nan'):.2f}", flush=True)
        Path(args.out).write_text(json.dumps({"rows": rows}))
    summary, lands = summarise(rows, design["equations"], args.soft_max)
    summary["seconds"] = round(time.perf_counter() - start, 1)
    print(json.dumps(summary, indent=1))
    Path(args.out).write_text(json.dumps({"summary": summary, "held_out": lands, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
