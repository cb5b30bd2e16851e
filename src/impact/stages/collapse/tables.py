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
    data = stats.CensoredData(interval=np.column_stack([low[found], np.log(runs["collapse_sa"].values[found])]),
                              right=low[~found])
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
                         "collapsed_share_at_MCE": float(np.mean(np.nan_to_num(sa, nan=np.inf) <= shared["S_MT_g"])),
                         "never_collapsed": int(np.isnan(sa).sum()), "unresolved": int(part["unresolved"].sum()),
                         "runs": int(part["runs"].sum()),
                         "runs_at_event_cap": int((part["run_event_cap_reached"].values == 1).sum()),
                         "max_energy_residual": float(np.nanmax(np.abs(part["run_energy_residual"].values)))})
    first = ["archetype", "damper", "mass_ratio", "group"]
    frame = pd.DataFrame(rows)
    return frame[first + [c for c in frame.columns if c not in first]]


def performance_groups(table: pd.DataFrame) -> pd.DataFrame:
    """P695's test of a performance group (7.6): per damper design, the mean ACMR of the archetypes under the
    far-field set against ACMR10 (with the largest beta_TOT among them), beside the least archetype's ACMR against
    ACMR20."""
    far = table[table.group == JUDGED_GROUP]
    rows = []
    for (kind, mr), part in far.groupby(["damper", "mass_ratio"], dropna=False, sort=False):
        beta = float(part.beta_TOT.max())
        mean = float(part.ACMR.mean())
        limit = acceptable_acmr(beta, PROBABILITIES["ACMR10"])
        rows.append({"damper": kind, "mass_ratio": mr, "archetypes": len(part), "mean_ACMR": mean,
                     "beta_TOT": beta, "ACMR10": limit, "passes_ACMR10": bool(mean >= limit),
                     "least_ACMR": float(part.ACMR.min()), "archetypes_passing_ACMR20": int(part.passes_ACMR20.sum())})
    return pd.DataFrame(rows)


def _paired_interval(statistic, records: np.ndarray, samples: int, seed: int, interval: float) -> tuple[float, float]:
    """The percentile interval of a statistic of the motions, resampling whole records (both components together,
    as they are not independent) with replacement.  Draws may be inf (a median above the hunt's top); a draw with
    no answer (NaN) is left out."""
    ids = np.unique(records)
    members = [np.flatnonzero(records == r) for r in ids]
    rng = np.random.default_rng(seed)
    draws = np.array([statistic(np.concatenate([members[i] for i in rng.integers(0, len(ids), len(ids))]))
                      for _ in range(samples)])
    draws = draws[~np.isnan(draws)]
    if not len(draws):
        return math.nan, math.nan
    tail = 0.5 * (1.0 - interval)
    return (float(np.quantile(draws, tail, method="inverted_cdf")),
            float(np.quantile(draws, 1.0 - tail, method="inverted_cdf")))


def median_ratio(damped: np.ndarray, plain: np.ndarray) -> float:
    """The damped median collapse intensity over the bare one: inf when only the damped one is above the hunt's
    top, NaN when the bare one is (no ratio can be read)."""
    bare_median = counted_median(plain)
    return math.nan if math.isinf(bare_median) else counted_median(damped) / bare_median


def verdicts(table: pd.DataFrame, bare: xr.Dataset, dampers: dict[str, xr.Dataset], cfg: dict) -> pd.DataFrame:
    """Per damper, mass ratio and record group: the median collapse intensity over the bare archetype's (same
    motions) with its bootstrap interval over records, and the ACMR's change with it."""
    v = cfg["verdict"]
    groups = bare["group"].values
    records = np.array([record_of(m) for m in bare["motion"].values])
    bare_sa = bare["collapse_sa"].values
    rows = []
    for kind, mr, runs in cases(bare, dampers):
        if kind == "bare":
            continue
        collapse_sa = runs["collapse_sa"].values
        for group in GROUPS:
            pick = np.flatnonzero(groups == group)
            if not len(pick):
                continue

            def ratio(idx, damped=collapse_sa[pick], plain=bare_sa[pick]):
                return median_ratio(damped[idx], plain[idx])

            lo, hi = _paired_interval(ratio, records[pick], v["bootstrap"], v["seed"], v["interval"])
            mine = table[(table.damper == kind) & (table.mass_ratio == mr) & (table.group == group)].iloc[0]
            base = table[(table.damper == "bare") & (table.group == group)].iloc[0]
            point = ratio(np.arange(len(pick)))
            rows.append({"archetype": bare.attrs["building"], "damper": kind, "mass_ratio": mr, "group": group,
                         "S_CT_over_bare": point, "S_CT_over_bare_low": lo, "S_CT_over_bare_high": hi,
                         "ACMR_bare": base.ACMR, "ACMR": mine.ACMR, "ACMR_change": base.ACMR * (point - 1.0),
                         "ACMR_change_low": base.ACMR * (lo - 1.0), "ACMR_change_high": base.ACMR * (hi - 1.0),
                         "unresolved": int(mine.unresolved + base.unresolved)})
    return pd.DataFrame(rows)


def best(verdict: pd.DataFrame, resolution: float) -> pd.DataFrame:
    """Per archetype and group: the damper design that raises the ACMR most ("none" if none raises it or none can be
    read; designs tied to round-off joined by "/"), and whether that is clear: its bootstrap interval of the median
    collapse intensity over the bare's lies above 1 by more than the hunt's resolution (each collapse intensity is
    known to that share only) and no motion of the comparison was left unresolved."""
    rows = []
    for (arch, group), part in verdict.groupby(["archetype", "group"], sort=False):
        read = part.dropna(subset=["ACMR_change"])
        if not len(read) or read.ACMR_change.max() <= 0:
            rows.append({"archetype": arch, "group": group, "damper": "none", "clear": False})
            continue
        top = read.loc[read["ACMR_change"].idxmax()]
        tied = read[read["ACMR_change"] >= top.ACMR_change - 1e-12 * abs(top.ACMR_bare)]
        rows.append({"archetype": arch, "group": group,
                     "damper": "/".join(f"{d}@{m:g}" for d, m in zip(tied.damper, tied.mass_ratio)),
                     "ACMR_bare": top.ACMR_bare, "ACMR": top.ACMR, "ACMR_change": top.ACMR_change,
                     "S_CT_over_bare": top.S_CT_over_bare, "S_CT_over_bare_low": top.S_CT_over_bare_low,
                     "clear": bool(top.S_CT_over_bare_low > 1.0 + resolution and top.unresolved == 0)})
    return pd.DataFrame(rows)


def _span(values, fmt: str = ".2f") -> str:
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    return f"{lo:{fmt}}" if f"{lo:{fmt}}" == f"{hi:{fmt}}" else f"{lo:{fmt}} to {hi:{fmt}}"


def summary(table: pd.DataFrame, verdict: pd.DataFrame, top: pd.DataFrame, groups: pd.DataFrame) -> str:
    """What the tables say, as the README and docs/results.md say it (a test holds them to this text)."""
    bare = table[(table.damper == "bare") & (table.group == JUDGED_GROUP)]
    unstable = bare[~bare.within_stability_limit]
    one_archetype = table[(table.damper == "bare") & (table.archetype == table.archetype.iloc[0])]
    bare_group = groups[groups.damper == "bare"].iloc[0]
    cases = len(top)
    kinds = sorted(verdict.damper.unique())
    sole = {kind: int(sum(name.split("@")[0] == kind and "/" not in name for name in top.damper)) for kind in kinds}
    per_kind = ", ".join(f"{kind.upper()} alone in {sole[kind]}" for kind in kinds)
    shared = int(sum("/" in name for name in top.damper))
    none = int((top.damper == "none").sum())
    leaders = [{name.split("@")[0] for name in names.split("/")} for names in top.damper if names != "none"]
    among = {kind: sum(kind in lead for lead in leaders) for kind in kinds}
    clear = top[top.clear]
    clear_by = ", ".join(f"{kind.upper()} {n}" for kind, n in
                         clear.damper.str.split("@").str[0].value_counts().sort_index().items()) or "none"
    larger = verdict[verdict.mass_ratio == verdict.mass_ratio.max()]
    changes = "; ".join(f"{kind.upper()} {_span(100.0 * (part.S_CT_over_bare - 1.0), '+.0f')} %"
                        for kind, part in larger.groupby("damper"))
    passing = groups[groups.passes_ACMR10]
    lines = [
        f"- **The bare archetypes** ({len(bare)}, designed by the configured rule) collapse at a median Sa(T1) of "
        f"{_span(bare.S_CT_g)} g far-field against an MCE demand of {_span(bare.S_MT_g)} g: ACMR {_span(bare.ACMR)} "
        f"against ACMR20 {_span(bare.ACMR20)}, so {int(bare.passes_ACMR20.sum())} of {len(bare)} pass FEMA P695's "
        f"test of one archetype (μ_T {_span(bare.mu_T, '.1f')}); their mean ACMR, {bare_group.mean_ACMR:.2f} "
        f"against ACMR10 {bare_group.ACMR10:.2f}, {'passes' if bare_group.passes_ACMR10 else 'fails'} the test of "
        f"the group. {len(unstable)} of {len(bare)} exceed ASCE 7's P-delta stability limit "
        f"θ ≤ {float(bare.stability_limit.iloc[0]):.3f} ({', '.join(unstable.archetype) or 'none'}).",
        f"- **Which damper raises the collapse margin most**, per archetype and record group ({cases} cases): "
        f"{per_kind}, tied in {shared}, none in {none}; {', '.join(f'the {k.upper()} leads or shares the lead in {among[k]}' for k in kinds)}. "
        f"The lead is clear (its interval above 1 by more than the hunt's resolution, every motion resolved) in "
        f"{int(top.clear.sum())} of {cases}: {clear_by}.",
        f"- **The change of the median collapse intensity** over the bare archetype's at "
        f"{100 * float(larger.mass_ratio.max()):g} % of the mass, over archetypes and groups: {changes}. "
        f"Designs whose archetypes pass the group's test (mean far-field ACMR ≥ ACMR10): "
        f"{', '.join(f'{d}@{m:g}' if d != 'bare' else 'bare' for d, m in zip(passing.damper, passing.mass_ratio)) or 'none'}.",
        f"- **The runs:** {int(table.runs.sum()):,} exact runs of hunt and fill, {len(bare) * len(groups)} cases "
        f"(archetype and damper design) of {int(one_archetype.motions.sum())} ground motions each; "
        f"{int(table.runs_at_event_cap.sum())} stopped at the event cap, "
        f"{int(table.unresolved.sum())} motions unresolved, {int(table.never_collapsed.sum())} motion traces standing "
        f"at the hunt's top; the largest energy residual {table.max_energy_residual.max():.1e}.",
    ]
    return "\n".join(lines) + "\n"
