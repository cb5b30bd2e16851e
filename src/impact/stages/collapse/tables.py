"""The collapse assessment's tables: FEMA P695's margins per archetype, case and record group, and the verdict on each
damper against the bare archetype (no simulation)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

from impact.model.suites import GROUPS, record_of
from impact.stages.collapse.p695 import (
    acceptable_acmr,
    collapse_probability,
    counted_median,
    spectral_shape_factor,
    total_uncertainty,
)
from impact.stages.resampling import cluster_draws

#: conditional collapse probabilities at MCE P695 judges a margin against: a performance group's mean (10 %), one
#: archetype (20 %)
PROBABILITIES = {"ACMR10": 0.10, "ACMR20": 0.20}
#: the record group P695's acceptance is calibrated on; the near-field groups are read beside it
JUDGED_GROUP = GROUPS[0]


def cases(bare: xr.Dataset, dampers: dict[str, xr.Dataset]):
    """(damper label, mass ratio, runs dataset) of the bare archetype and each damper at each mass ratio."""
    yield "bare", math.nan, bare
    for kind, ds in dampers.items():
        for mr in ds["mass_ratio"].values:
            yield kind, float(mr), ds.sel(mass_ratio=mr)


def lognormal_fit(runs: xr.Dataset) -> tuple[float, float]:
    """Median and dispersion of a lognormal fitted by maximum likelihood (scipy's CensoredData): each collapse
    intensity known only within its bracket (standing_sa, collapse_sa], a motion without one censored above its
    last level that stood."""
    found = ~np.isnan(runs["collapse_sa"].values)
    if found.sum() < 2:
        return math.nan, math.nan
    with np.errstate(divide="ignore"):
        low = np.log(runs["standing_sa"].values)
    censored = low[~found]
    # a motion whose first run stood nowhere (unresolved at its first level) says nothing: it is left out
    data = stats.CensoredData(interval=np.column_stack([low[found], np.log(runs["collapse_sa"].values[found])]),
                              right=censored[np.isfinite(censored)])
    mu, sigma = stats.norm.fit(data)
    return float(math.exp(mu)), float(sigma)


def _archetype(bare: xr.Dataset, cfg: dict) -> dict:
    """The columns every row of an archetype shares: its periods, stability, mu_T and P695's limits."""
    a = bare.attrs
    beta_tot = total_uncertainty(cfg["ratings"], float(a["mu_T"]))
    theta = float(bare["stability_coefficient"].max())
    return {"archetype": a["building"], "period_s": float(a["period_s"]), "code_period_s": float(a["code_period_s"]),
            "theta_max": theta, "stability_limit": float(a["stability_limit"]),
            "within_stability_limit": bool(theta <= float(a["stability_limit"])),
            "mu_T": float(a["mu_T"]), "S_MT_g": float(a["S_MT_g"]), "beta_TOT": beta_tot,
            **{name: acceptable_acmr(beta_tot, p) for name, p in PROBABILITIES.items()}}


def margins(bare: xr.Dataset, dampers: dict[str, xr.Dataset], cfg: dict) -> pd.DataFrame:
    """One row per case and record group: FEMA P695's collapse margin numbers.  The archetype's pushover (its
    mu_T) is the bare building's: a damper on the roof adds no static strength."""
    shared = _archetype(bare, cfg)
    groups = bare["group"].values
    rows = []
    for kind, mr, runs in cases(bare, dampers):
        for group in GROUPS:
            pick = groups == group
            if not pick.any():
                continue
            part = runs.isel(motion=np.flatnonzero(pick))
            sa = part["collapse_sa"].values
            s_ct = counted_median(sa)
            fit_median, fit_beta = lognormal_fit(part)
            ssf = spectral_shape_factor(shared["period_s"], shared["mu_T"], cfg["sdc"], group)
            acmr = ssf * s_ct / shared["S_MT_g"]
            rows.append({**shared, "damper": kind, "mass_ratio": mr, "group": group, "motions": int(pick.sum()),
                         "S_CT_g": s_ct, "S_CT_fit_g": fit_median, "beta_RTR_fit": fit_beta,
                         "CMR": s_ct / shared["S_MT_g"], "SSF": ssf, "ACMR": acmr,
                         "P_collapse_MCE": collapse_probability(acmr, shared["beta_TOT"]),
                         "passes_ACMR20": bool(acmr >= shared["ACMR20"]),
                         "marginal": bool(abs(acmr / shared["ACMR20"] - 1.0) < cfg["resolution"]),
                         "collapsed_share_at_MCE": float(np.mean(np.nan_to_num(sa, nan=np.inf) <= shared["S_MT_g"])),
                         "never_collapsed": int(np.isnan(sa).sum()), "unresolved": int(part["unresolved"].sum()),
                         "runs": int(part["runs"].sum()),
                         "runs_at_event_cap": int((part["run_event_cap_reached"].values == 1).sum()),
                         "max_energy_residual": float(np.nanmax(np.abs(part["run_energy_residual"].values)))})
    first = ["archetype", "damper", "mass_ratio", "group"]
    frame = pd.DataFrame(rows)
    return frame[first + [c for c in frame.columns if c not in first]]


def performance_groups(table: pd.DataFrame, resolution: float) -> pd.DataFrame:
    """P695's test of a performance group (7.6): per damper design, the mean far-field ACMR of the archetypes against
    ACMR10 (with the largest beta_TOT among them) and every archetype's against ACMR20; accepted when both hold.
    `marginal`: the mean is within the hunt's resolution of ACMR10 (each collapse intensity is known to that share)."""
    far = table[table.group == JUDGED_GROUP]
    rows = []
    for (kind, mr), part in far.groupby(["damper", "mass_ratio"], dropna=False, sort=False):
        beta = float(part.beta_TOT.max())
        mean = float(part.ACMR.mean())
        limit = acceptable_acmr(beta, PROBABILITIES["ACMR10"])
        passing = int(part.passes_ACMR20.sum())
        rows.append({"damper": kind, "mass_ratio": mr, "archetypes": len(part), "mean_ACMR": mean,
                     "beta_TOT": beta, "ACMR10": limit, "passes_ACMR10": bool(mean >= limit),
                     "marginal": bool(abs(mean / limit - 1.0) < resolution), "least_ACMR": float(part.ACMR.min()),
                     "archetypes_passing_ACMR20": passing,
                     "accepted": bool(mean >= limit and passing == len(part))})
    return pd.DataFrame(rows)


def _paired_interval(statistic, records: np.ndarray, samples: int, seed: int,
                     interval: float) -> tuple[float, float, float]:
    """The percentile interval of a statistic of the motions, resampling whole records (both components together,
    as they are not independent) with replacement, and the share of draws left out for having no answer (NaN: a
    resample whose bare median is above the hunt's top).  Draws may be inf (a damped median above the top)."""
    draws = cluster_draws(statistic, records, samples, seed)
    read = draws[~np.isnan(draws)]
    unread = 1.0 - len(read) / len(draws)
    if not len(read):
        return math.nan, math.nan, unread
    tail = 0.5 * (1.0 - interval)
    return (float(np.quantile(read, tail, method="inverted_cdf")),
            float(np.quantile(read, 1.0 - tail, method="inverted_cdf")), unread)


def median_ratio(damped: np.ndarray, plain: np.ndarray) -> float:
    """The damped median collapse intensity over the bare one: inf when only the damped one is above the hunt's
    top, NaN when the bare one is (no ratio can be read)."""
    bare_median = counted_median(plain)
    return math.nan if math.isinf(bare_median) else counted_median(damped) / bare_median


def verdicts(table: pd.DataFrame, bare: xr.Dataset, dampers: dict[str, xr.Dataset], cfg: dict) -> pd.DataFrame:
    """Per damper, mass ratio and record group: the median collapse intensity over the bare archetype's (same
    motions) with its bootstrap interval over records, the ACMR's change with it, and whether the rise is clear:
    the interval above 1 by more than the hunt's resolution, every motion of the comparison resolved."""
    v, resolution = cfg["verdict"], cfg["resolution"]
    groups = bare["group"].values
    records = np.array([record_of(m) for m in bare["motion"].values])
    bare_sa = bare["collapse_sa"].values
    rows = []
    for kind, mr, runs in cases(bare, dampers):
        if kind == "bare":
            continue
        if not np.array_equal(runs["motion"].values, bare["motion"].values):
            raise ValueError(f"collapse: the {kind} runs are not over the bare archetype's ground motions")
        collapse_sa = runs["collapse_sa"].values
        for group in GROUPS:
            pick = np.flatnonzero(groups == group)
            if not len(pick):
                continue

            def ratio(idx, damped=collapse_sa[pick], plain=bare_sa[pick]):
                return median_ratio(damped[idx], plain[idx])

            lo, hi, unread = _paired_interval(ratio, records[pick], v["bootstrap"], v["seed"], v["interval"])
            mine = table[(table.damper == kind) & (table.mass_ratio == mr) & (table.group == group)].iloc[0]
            base = table[(table.damper == "bare") & (table.group == group)].iloc[0]
            point = ratio(np.arange(len(pick)))
            unresolved = int(mine.unresolved + base.unresolved)
            rows.append({"archetype": bare.attrs["building"], "damper": kind, "mass_ratio": mr, "group": group,
                         "S_CT_over_bare": point, "S_CT_over_bare_low": lo, "S_CT_over_bare_high": hi,
                         "unread_draws": unread, "ACMR_bare": base.ACMR, "ACMR": mine.ACMR,
                         "ACMR_change": base.ACMR * (point - 1.0), "ACMR_change_low": base.ACMR * (lo - 1.0),
                         "ACMR_change_high": base.ACMR * (hi - 1.0), "unresolved": unresolved,
                         "clear": bool(lo > 1.0 + resolution and unresolved == 0)})
    return pd.DataFrame(rows)


def _types(designs: pd.DataFrame) -> str:
    return "+".join(sorted(set(designs.damper)))


def best(verdict: pd.DataFrame, resolution: float) -> pd.DataFrame:
    """Per archetype and group: the damper designs that raise the median collapse intensity (and so the ACMR) most,
    every design within the hunt's resolution of the top counted as tied with it ("none": no design raises it;
    "unread": no ratio can be read), their damper types, and the types among them whose rise is clear."""
    rows = []
    for (arch, group), part in verdict.groupby(["archetype", "group"], sort=False):
        read = part.dropna(subset=["S_CT_over_bare"])
        top = float(read.S_CT_over_bare.max()) if len(read) else math.nan
        row = {"archetype": arch, "group": group}
        if not len(read) or top <= 1.0:
            rows.append(row | {"designs": "unread" if not len(read) else "none", "types": "", "clear_types": ""})
            continue
        leaders = read[(read.S_CT_over_bare >= top / (1.0 + resolution)) & (read.S_CT_over_bare > 1.0)]
        first = leaders.loc[leaders.S_CT_over_bare.idxmax()]
        rows.append(row | {"designs": "/".join(f"{d}@{m:g}" for d, m in zip(leaders.damper, leaders.mass_ratio)),
                           "types": _types(leaders), "clear_types": _types(leaders[leaders.clear]),
                           "S_CT_over_bare": top, "ACMR_bare": first.ACMR_bare,
                           "ACMR_change": float(leaders.ACMR_change.max())})
    return pd.DataFrame(rows)


def _span(values, fmt: str = ".2f") -> str:
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    return f"{lo:{fmt}}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}} to {hi:{fmt}}"


def _designs(groups: pd.DataFrame, pick) -> str:
    rows = groups[pick]
    return ", ".join("bare" if d == "bare" else f"{d}@{m:g}" for d, m in zip(rows.damper, rows.mass_ratio)) or "none"


def summary(table: pd.DataFrame, verdict: pd.DataFrame, top: pd.DataFrame, groups: pd.DataFrame) -> str:
    """What the tables say, as the README and docs/results.md say it (a test holds them to this text)."""
    bare = table[(table.damper == "bare") & (table.group == JUDGED_GROUP)]
    unstable = bare[~bare.within_stability_limit]
    one_archetype = table[(table.damper == "bare") & (table.archetype == table.archetype.iloc[0])]
    bare_group = groups[groups.damper == "bare"].iloc[0]
    cases = len(top)
    kinds = sorted(verdict.damper.unique())
    leading = [set(t.split("+")) - {""} for t in top.types.fillna("")]
    clear = [set(t.split("+")) - {""} for t in top.clear_types.fillna("")]
    alone = {kind: sum(lead == {kind} for lead in leading) for kind in kinds}
    shared = sum(len(lead) > 1 for lead in leading)
    among = {kind: sum(kind in lead for lead in leading) for kind in kinds}
    clear_top = {kind: sum(kind in c for c in clear) for kind in kinds}
    clear_any = {kind: f"{int(part.clear.sum())} of {len(part)}" for kind, part in verdict.groupby("damper")}
    larger = verdict[verdict.mass_ratio == verdict.mass_ratio.max()]
    changes = "; ".join(f"{kind.upper()} {_span(100.0 * (part.S_CT_over_bare - 1.0), '+.0f')} %"
                        for kind, part in larger.groupby("damper"))
    lines = [
        f"- **The bare archetypes** ({len(bare)}, designed by the configured rule) collapse at a median Sa(T1) of "
        f"{_span(bare.S_CT_g)} g far-field against an MCE demand of {_span(bare.S_MT_g)} g: ACMR {_span(bare.ACMR)} "
        f"against ACMR20 {_span(bare.ACMR20)}, so {int(bare.passes_ACMR20.sum())} of {len(bare)} pass FEMA P695's "
        f"test of one archetype ({int(bare.marginal.sum())} within the hunt's resolution of the limit; μ_T "
        f"{_span(bare.mu_T, '.1f')}); their mean ACMR, {bare_group.mean_ACMR:.2f} against ACMR10 "
        f"{bare_group.ACMR10:.2f}, {'passes' if bare_group.passes_ACMR10 else 'fails'} the test of the group. "
        f"{len(unstable)} of {len(bare)} exceed ASCE 7's P-delta stability limit "
        f"θ ≤ {float(bare.stability_limit.iloc[0]):.3f} ({', '.join(unstable.archetype) or 'none'}).",
        f"- **Which damper raises the median collapse intensity most**, per archetype and record group ({cases} "
        f"cases; designs within the hunt's resolution of the best counted as tied): "
        + ", ".join(f"{kind.upper()} alone in {alone[kind]}" for kind in kinds)
        + f", two types or more in {shared}, none in {int((top.designs == 'none').sum())}; "
        + ", ".join(f"the {kind.upper()} among the leaders in {among[kind]}" for kind in kinds)
        + ". Among the leaders a rise is clear (its interval above 1 by more than the resolution, every motion "
        + "resolved) for " + ", ".join(f"the {kind.upper()} in {clear_top[kind]}" for kind in kinds) + ".",
        f"- **The change of the median collapse intensity** over the bare archetype's at "
        f"{100 * float(larger.mass_ratio.max()):g} % of the mass, over archetypes and groups: {changes}. Clear "
        f"rises, over every design and group: " + ", ".join(f"{kind.upper()} {clear_any[kind]}" for kind in kinds)
        + f". The archetypes as a group: mean far-field ACMR ≥ ACMR10 for {_designs(groups, groups.passes_ACMR10)} "
        f"(within the resolution of it: {_designs(groups, groups.passes_ACMR10 & groups.marginal)}); accepted "
        f"(and every archetype ≥ ACMR20) for {_designs(groups, groups.accepted)}.",
        f"- **The runs:** {int(table.runs.sum()):,} exact runs of hunt and fill, {len(bare) * len(groups)} cases "
        f"(archetype and damper design) of {int(one_archetype.motions.sum())} ground motions each; "
        f"{int(table.runs_at_event_cap.sum())} stopped at the event cap, "
        f"{int(table.unresolved.sum())} motions unresolved, {int(table.never_collapsed.sum())} motion traces standing "
        f"at the hunt's top; the largest energy residual {table.max_energy_residual.max():.1e}.",
    ]
    return "\n".join(lines) + "\n"
