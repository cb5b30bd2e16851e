"""The study's HTML report, built from the result files only.

``build_report`` writes one self-contained page (``results/report/index.html``):
every figure is embedded as a base64 PNG data URI, every table is read from
its CSV/JSON file at build time, and the page loads no external resource (no
script, font, stylesheet or CDN).  No number is typed into this module: the
text it adds around the data is either the paper's own values (quoted as the
paper's) or computed from the result files, so the report cannot drift from
the data it shows.

Sections are a plain ordered list of dicts::

    {"id": "fig08", "title": "Fig. 8 ...", "kind": "figure", "path": "results/figures/fig08.png",
     "caption": "optional; default from CAPTIONS"}

with ``kind`` one of ``text`` (``text``: plain text, or ``html``: trusted
markup), ``table`` (``path``: a .csv or .json file; optional ``highlight``:
``{"column": ..., "equals": ...}``, optional ``summary``) or ``figure``
(``path``: a PNG).  A section whose file does not exist is left out.
``standard_sections`` assembles the study's list from whatever result files
exist; ``collect_provenance`` gathers the run's provenance (git state,
package versions, config hash, per-job run times, executor).
"""

from __future__ import annotations

import base64
import csv
import hashlib
import html
import json
import logging
import re
import struct
from collections.abc import Iterable, Mapping
from pathlib import Path

from .io import write_text_atomic

log = logging.getLogger(__name__)

KINDS = ("text", "table", "figure")

# --------------------------------------------------------------------------- data: texts and captions

OVERVIEW_HTML = """
<p>This report regenerates the parametric study of <em>Chua, Pacheco, Fujino and Ito</em>,
&#8220;Classical impact damper and pendulum impact damper for potential civil engineering
application&#8221;, on three dampers attached to a lightly damped structure under harmonic force:
the <strong>classical impact damper</strong> (CID, a free mass rattling between two walls),
the <strong>pendulum impact damper</strong> (PID, a pendulum striking the same walls) and the
<strong>tuned mass damper</strong> (TMD) as the reference.</p>
<p><strong>Model.</strong> The structure is a single-degree-of-freedom oscillator (damping ratio
&#946;, natural frequency &#969; = 1) forced by F<sub>0</sub> sin &#937;t. The damper mass
m = &#956;M moves freely (CID) or as a linearised pendulum tuned to r&#8242; = &#969;<sub>p</sub>/&#969;
(PID) inside a clearance d. Impacts are instantaneous, conserve momentum and reverse the relative
velocity with the coefficient of restitution e. Between impacts the motion is linear, so the
simulator advances it in closed form and locates every impact to round-off.</p>
<p><strong>Protocol.</strong> In the paper each run starts from rest and lasts 500 natural periods;
the amplitude is &#8730;2 times the RMS of the displacement over the second half. A frequency sweep
r = &#937;/&#969; around resonance gives the largest amplitude x<sub>max</sub>, reported as the
amplitude ratio X<sub>m</sub> = x<sub>max</sub>/A<sub>max</sub> against the gap ratio
g = d/A<sub>max</sub>, where A<sub>max</sub> is the bare structure's resonant amplitude. The impacts
per cycle at the largest amplitude are classified as in the paper (&lt;1, 1, 2, &gt;2 IPC).</p>
<p><strong>Initial conditions.</strong> The paper does not say where the damper mass starts. The CID
has coexisting steady states, so every CID curve is run with the mass centred and with the mass
resting against a wall, and both are kept and shown.</p>
<p><strong>How to read this report.</strong> Every table and figure below is read from the result
files of this run when the report is built. The table of the paper&#8217;s reported values beside
ours highlights each value that differs by more than 10 % and gives the reason the pipeline found;
the model is never adjusted to hit a number. The last section records where the results came from:
the commit, the package versions, a hash of the configuration and the run time of every job.</p>
"""

# Default captions of the study's figures (plain text; the paper's values only, quoted as the paper's).
CAPTIONS = {
    "fig08": (
        "Fig. 8 of the paper: the effect of the mass ratio (μ = 0.01 and 0.03) on the amplitude ratio "
        "X_m = x_max / A_max against the gap ratio g = d / A_max, for the CID (a) and the PID tuned to "
        "r' = 0.5, 1.0 and 1.5 (b-d); β = 0.0048, e = 0.25, A_max = 10. Markers give the impacts-per-cycle "
        "class at the largest amplitude (filled circles: 2 IPC). CID curves are drawn for both starts of the "
        "damper mass: centred (solid) and against the left wall (dotted).\n\n"
        "The paper reads X_m = 0.32 at the optimum gap for the CID and 0.42 / 0.50 / 0.80 for the PID with "
        "r' = 0.5 / 1.0 / 1.5 (μ = 0.01), with 2 IPC over g = 0.8-1.2, 0.8-4.4 and 0.6-1.0, and over "
        "g = 0.4-1.6 for r' = 1.0 with μ = 0.03. Its conclusion, that a larger mass generally lowers X_m "
        "(except for the PID with r' > 1) and shortens the 2-IPC range towards smaller gaps, can be checked "
        "against the curves; the reproduced values are in the table of reported values."
    ),
    "fig09": (
        "Fig. 9 of the paper: the effect of the coefficient of restitution (e = 0.25, 0.45, 0.65) on the "
        "amplitude ratio X_m against the gap ratio g, for the CID (a) and the PID with r' = 0.5, 1.0, 1.5 "
        "(b-d); μ = 0.01, β = 0.0048, A_max = 10. Markers give the impacts-per-cycle class at the "
        "largest amplitude; CID curves are drawn for both starts of the damper mass (centred solid, left "
        "wall dotted).\n\n"
        "The paper reads, for the CID, X_m = 0.32 / 0.22 / 0.40 at the optimum gap for e = 0.25 / 0.45 / "
        "0.65 (the best damper has a medium e), and for the PID curves that rise monotonically with e. "
        "The table of reported values gives ours beside each."
    ),
    "fig10": (
        "Fig. 10 of the paper: the effect of Coulomb friction under the CID's mass (ν = 0 to 0.5) on X_m "
        "against g (μ = 0.01, β = 0.0048, e = 0.25). The paper finds that friction lowers the CID's "
        "efficiency; it does not give the length and time scale friction needs, so the scale used here "
        "is the configured one (see the configuration hash below)."
    ),
    "fig11": (
        "Fig. 11 of the paper: the CID and the PID (r' = 0.5, 1.0, 1.5), all with μ = 0.01 and e = 0.25, "
        "against the gap ratio g, with the optimum TMD of the same mass as a dashed horizontal line "
        "(equal-peak optimum of the tuning f and damping β_t); β = 0.0048, A_max = 10.\n\n"
        "The paper's TMD optimum is f = 0.99, β_t = 0.06, and its efficiency order is TMD > CID > PID. "
        "The table of reported values gives our optimum and whether the order holds for each start of "
        "the CID's mass."
    ),
}
CAPTIONS.update({
    "masri_stability": (
        "Masri's closed-form solution with two equally spaced impacts per cycle (2 EIPC) for the CID: where "
        "it exists and where it is stable, in the plane of the frequency ratio r and the clearance "
        "d / (F0/K), one panel per coefficient of restitution. The paper uses this closed form to check "
        "its simulation in the 2-EIPC range; the table of the closed-form check compares the simulator "
        "with it point by point."
    ),
    "masri_branches": (
        "The closed-form 2-EIPC branches of the CID (stable: solid, unstable: dashed) against the "
        "simulator's runs from rest. Where a run from rest lands on a stable branch the two agree to "
        "round-off; where it does not, the motion from rest has found another steady state."
    ),
})
# Captions of figures drawn once per curve, by the start of their file name.
CAPTION_PREFIXES = {
    "coexistence_": (
        "Coexisting steady states of {curve}: X_m against g from rest, from both directions of a "
        "continuation in frequency, and the envelope of an ensemble of initial conditions. The paper "
        "does not say where its damper mass started; the spread between these curves is how much that "
        "choice can matter."
    ),
    "hysteresis_": (
        "Frequency response of {curve} at one gap: the up-sweep and down-sweep continuation branches and "
        "the closed-form 2-EIPC branch. Where the branches differ the response depends on its history."
    ),
}
GENERIC_FIGURE_CAPTION = "{name}: drawn from the study's result files when this report was built."

# Figure numbers of the paper for each figure id (to pick that figure's rows of the comparison table).
_FIG_NUMBER = re.compile(r"^fig0*(\d+)$")

STANDARD_TABLES = {
    # id: (path under results/, title)
    "paper_vs_reproduced": ("tables/paper_vs_reproduced.csv", "The paper's reported values beside ours"),
    "tmd_optimum": ("tables/tmd_optimum.json", "Optimum tuned mass damper"),
    "masri_check": ("tables/masri_check.csv", "Check against Masri's closed form (2 EIPC)"),
    "masri_summary": ("checks/masri_summary.json", "Closed-form check: summary"),
    "coexistence": ("tables/coexistence.csv", "Coexisting steady states"),
    "cross_validation": ("tables/cross_validation.csv", "Cross-validation of the simulator"),
    "numerics_stability": ("tables/numerics_stability.csv", "Numerics: stability of the integrators"),
}
STANDARD_FIGURES_EXTRA = {
    "numerics_error_runtime": ("figures/numerics_error_runtime.png", "Numerics: error against run time"),
}
TABLE_CAPTIONS = {
    "paper_vs_reproduced": (
        "Every value the paper reports, next to ours. Rows where ours differ by more than 10 % (or where "
        "a qualitative statement does not hold) are highlighted; the reason column says why, as far as "
        "the data can tell."
    ),
    "tmd_optimum": (
        "The equal-peak (minimax) optimum of a TMD with the study's mass ratio on the study's structure, "
        "with Den Hartog's closed-form values (undamped structure) for comparison. The paper's optimum is "
        "f = 0.99, β_t = 0.06."
    ),
    "masri_check": (
        "The simulator's steady state against Masri's closed-form two-equally-spaced-impacts-per-cycle "
        "solution, where that solution exists and is stable."
    ),
    "masri_summary": "The closed-form check summarised by start of the damper mass and by the orbit's stability margin.",
    "coexistence": "Steady states reached from rest, by continuation in frequency and from an ensemble of starts.",
    "cross_validation": "The exact event-driven core against independent integrators on the same cases.",
    "numerics_stability": (
        "Which integrators stay stable, and where, on the study's cases. ok means finished and within "
        "tolerance: penetration at most 1e-6 of the gap and an amplitude within 1e-3 of the exact core's."
    ),
    "numerics_error_runtime": (
        "Error against run time of the exact event-driven core and of the baseline integrators on the "
        "same cases; lower left is better."
    ),
}

# Snakemake's own report (`snakemake --report`): categories by paper section.
SNAKEMAKE_CATEGORIES = {
    "fig08": ("5. Parametric study", "Fig. 8: mass ratio"),
    "fig09": ("5. Parametric study", "Fig. 9: coefficient of restitution"),
    "fig10": ("5. Parametric study", "Fig. 10: friction"),
    "fig11": ("6. Comparison of CID, PID and TMD", "Fig. 11: efficiency"),
    "tmd_optimum": ("6. Comparison of CID, PID and TMD", "TMD optimum"),
    "paper_vs_reproduced": ("Reproduction", "Paper vs reproduced"),
    "masri_check": ("Closed-form check (Masri, 2 EIPC)", "Point by point"),
    "masri_stability": ("Closed-form check (Masri, 2 EIPC)", "Existence and stability"),
    "masri_branches": ("Closed-form check (Masri, 2 EIPC)", "Branches and runs from rest"),
    "coexistence": ("Initial conditions and coexisting states", "Table"),
    "coexistence_": ("Initial conditions and coexisting states", "Coexisting states"),
    "hysteresis_": ("Initial conditions and coexisting states", "Hysteresis"),
}


def _category(name: str) -> tuple[str, str]:
    if name in SNAKEMAKE_CATEGORIES:
        return SNAKEMAKE_CATEGORIES[name]
    for prefix, value in SNAKEMAKE_CATEGORIES.items():
        if prefix.endswith("_") and name.startswith(prefix):
            return value
    return ("Other results", name)


def snakemake_category(name: str) -> str:
    """Category of a result in Snakemake's report (by paper section), for report(category=...)."""
    return _category(name)[0]


def snakemake_subcategory(name: str) -> str:
    return _category(name)[1]


# --------------------------------------------------------------------------- provenance


def canonical_json(obj) -> str:
    """One text for one value: sorted keys, no whitespace, UTF-8 kept, non-JSON types as str."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=True, default=str)


def config_hash(config) -> str:
    """sha256 of the canonical JSON of the configuration."""
    return hashlib.sha256(canonical_json(config).encode("utf-8")).hexdigest()


def read_benchmarks(paths: Iterable) -> list[dict]:
    """Per-job run times from Snakemake benchmark TSV files (column ``s``, seconds).

    A file's rule is the folder under ``benchmarks/`` (``benchmarks/figure/fig08.tsv``: rule
    ``figure``, job ``fig08``) or, directly in it, the file's name (``benchmarks/tmd_optimum.tsv``).
    A file benchmarked with repeats gives the mean of its rows.
    """
    out = []
    for path in sorted({Path(p) for p in paths}):
        parts = path.parts
        folders = [i for i, p in enumerate(parts[:-1]) if p == "benchmarks"]
        rel = list(parts[folders[-1] + 1:]) if folders else [path.name]
        rel[-1] = rel[-1].removesuffix(".tsv")
        rule, job = (rel[0], "/".join(rel[1:])) if len(rel) > 1 else (rel[0], "")
        try:
            with open(path, newline="") as fh:
                rows = list(csv.DictReader(fh, delimiter="\t"))
            seconds = [float(r["s"]) for r in rows if r.get("s") not in (None, "", "NA")]
        except (OSError, KeyError, ValueError) as exc:
            log.warning("benchmark %s unreadable: %s", path, exc)
            continue
        if not seconds:
            continue
        out.append({"rule": rule, "job": job, "s": sum(seconds) / len(seconds), "repeats": len(seconds),
                    "path": str(path)})
    return out


def find_benchmarks(root) -> list[Path]:
    """Every ``*.tsv`` under a benchmark folder (results/benchmarks/**/*.tsv)."""
    root = Path(root)
    return sorted(root.rglob("*.tsv")) if root.is_dir() else []


def collect_provenance(config=None, executor: str = "unknown", benchmarks: Iterable | None = None,
                       generated: str | None = None) -> dict:
    """The run's provenance as the report shows it.

    benchmarks: benchmark TSV paths (or a folder to search); executor: the Snakemake executor's
    name as the caller knows it (``local``, ``slurm``, ...).
    """
    from . import __version__
    from .provenance import git_state, now_utc, package_versions

    if benchmarks is None:
        bench_paths = []
    elif isinstance(benchmarks, (str, Path)):
        bench_paths = find_benchmarks(benchmarks) if Path(benchmarks).is_dir() else [Path(benchmarks)]
    else:
        bench_paths = [Path(p) for p in benchmarks]
    state = git_state()
    return {
        "git_commit": state["git_commit"],
        "git_dirty": state["git_dirty"],
        "code_version": __version__,
        "packages": package_versions(),
        "config_sha256": config_hash(config) if config is not None else None,
        "executor": str(executor),
        "benchmarks": read_benchmarks(bench_paths),
        "generated": generated or now_utc(),
    }


# --------------------------------------------------------------------------- sections


def figure_caption(name: str) -> str:
    if name in CAPTIONS:
        return CAPTIONS[name]
    for prefix, text in CAPTION_PREFIXES.items():
        if name.startswith(prefix) and len(name) > len(prefix):
            return text.format(curve=name[len(prefix):])
    return GENERIC_FIGURE_CAPTION.format(name=name)


def _figure_group(name: str) -> str:
    if _FIG_NUMBER.match(name):
        return "paper"
    if name.startswith("masri_"):
        return "masri"
    if name.startswith(("coexistence_", "hysteresis_")):
        return "coexistence"
    if name in STANDARD_FIGURES_EXTRA or name.startswith("numerics_"):
        return "numerics"
    return "other"


def standard_sections(results, figures: Iterable | None = None, captions: Mapping | None = None,
                      overview: bool = True, extra: Mapping | None = None, config: Mapping | None = None,
                      tables: Iterable = ()) -> list[dict]:
    """The study's sections, in order, for the result files under ``results`` that exist.

    Order: the study; the paper's values beside ours; the paper's figures; the TMD optimum; the
    closed-form check (tables, figures); coexisting states; cross-validation; numerics; any other
    figure; any other table.  figures: image paths (default: results/figures/*.png); captions:
    caption per section id, over the defaults; extra: {id: path} for a standard table or figure
    kept elsewhere than its standard place; config: the run's configuration, summarised in the
    overview (so the protocol stated is this run's); tables: further CSV/JSON tables, shown last.
    """
    results = Path(results)
    captions = dict(captions or {})
    extra = {k: Path(v) for k, v in (extra or {}).items()}
    sections: list[dict] = []
    if overview:
        sections.append({"id": "overview", "title": "The study", "kind": "text",
                         "html": OVERVIEW_HTML + (run_summary_html(config) if config else "")})

    def table(sid):
        rel, title = STANDARD_TABLES[sid]
        path = extra.get(sid, results / rel)
        if path.is_file():
            sec = {"id": sid, "title": title, "kind": "table", "path": str(path),
                   "caption": captions.get(sid, TABLE_CAPTIONS.get(sid, ""))}
            if sid == "paper_vs_reproduced":
                sec["highlight"] = {"column": "within_10pct", "equals": "False"}
                sec["comparison"] = True
            sections.append(sec)

    if figures is None:
        figures = sorted((results / "figures").glob("*.png"))
        figures += [p for sid, p in extra.items() if sid in STANDARD_FIGURES_EXTRA and p not in figures]
        figures += [results / rel for sid, (rel, _) in STANDARD_FIGURES_EXTRA.items()
                    if sid not in extra and (results / rel) not in figures]
    by_group: dict[str, list[dict]] = {}
    for path in figures:
        path = Path(path)
        if not path.is_file() or path.suffix.lower() not in _MIME:  # a PDF twin is not embedded
            continue
        name = path.stem
        sid = next((k for k, v in extra.items() if v == path), None) or html_id(name)
        by_group.setdefault(_figure_group(sid), []).append(
            {"id": sid, "title": _figure_title(name), "kind": "figure", "path": str(path),
             "caption": captions.get(sid, TABLE_CAPTIONS.get(sid) or figure_caption(name))})

    table("paper_vs_reproduced")
    sections += by_group.get("paper", [])
    table("tmd_optimum")
    table("masri_check")
    table("masri_summary")
    sections += by_group.get("masri", [])
    table("coexistence")
    sections += by_group.get("coexistence", [])
    table("cross_validation")
    sections += by_group.get("numerics", [])
    table("numerics_stability")
    sections += by_group.get("other", [])
    for path in tables:
        path = Path(path)
        if path.is_file():
            sid = html_id(path.stem)
            sections.append({"id": sid, "title": captions.get(f"{sid}:title", path.stem.replace("_", " ")),
                             "kind": "table", "path": str(path), "caption": captions.get(sid, "")})
    return sections


def html_id(name: str) -> str:
    """A valid, readable HTML id from a file's stem."""
    out = re.sub(r"[^A-Za-z0-9_.:-]+", "-", name).strip("-") or "section"
    return out if out[0].isalpha() else f"s-{out}"


def _num(x) -> str:
    return _e(format(x, "g")) if isinstance(x, (int, float)) and not isinstance(x, bool) else _e(x)


def _grid(g) -> str:
    if isinstance(g, Mapping) and {"min", "max", "step"} <= set(g):
        return f"{_num(g['min'])} to {_num(g['max'])} in steps of {_num(g['step'])}"
    if isinstance(g, (list, tuple)):
        return ", ".join(_num(x) for x in g)
    return _num(g)


def run_summary_html(config: Mapping) -> str:
    """The protocol of this run, read from its configuration (HTML, every value escaped)."""
    bits = []
    proto = config.get("protocol") or {}
    if "periods" in proto:
        text = f"{_num(proto['periods'])} natural periods per run"
        if "average_from" in proto:
            text += f", amplitude measured from period {_num(proto['average_from'])} on"
        bits.append(text)
    if "freq" in proto:
        bits.append(f"r = {_grid(proto['freq'])}")
    if "gap" in proto:
        bits.append(f"g = {_grid(proto['gap'])}")
    starts = proto.get("starts")
    if isinstance(starts, Mapping):
        bits.append("starts of the damper mass: " + "; ".join(
            f"{_e(str(k).upper())} {_grid(v)}" for k, v in starts.items()))
    struct_ = config.get("structure") or {}
    if "beta" in struct_:
        bits.append(f"&#946; = {_num(struct_['beta'])}")
    if "force_ratio" in struct_:
        bits.append(f"F<sub>0</sub>/K = {_num(struct_['force_ratio'])}")
    figures = config.get("figures")
    if isinstance(figures, Mapping) and figures:
        bits.append("figures " + ", ".join(_e(f) for f in figures))
    if not bits:
        return ""
    return f'<p id="this-run"><strong>This run</strong> (from its configuration): {"; ".join(bits)}.</p>'


def _figure_title(name: str) -> str:
    m = _FIG_NUMBER.match(name)
    if m:
        titles = {8: "the effect of the mass ratio", 9: "the effect of the coefficient of restitution",
                  10: "the effect of friction", 11: "CID, PID and the optimum TMD"}
        n = int(m.group(1))
        return f"Fig. {n}: {titles[n]}" if n in titles else f"Fig. {n}"
    named = {"masri_stability": "Masri's closed form: existence and stability",
             "masri_branches": "Masri's closed form: branches and runs from rest",
             "numerics_error_runtime": "Numerics: error against run time"}
    if name in named:
        return named[name]
    for prefix, title in (("coexistence_", "Coexisting steady states"), ("hysteresis_", "Hysteresis")):
        if name.startswith(prefix) and len(name) > len(prefix):
            return f"{title}: {name[len(prefix):]}"
    return name.replace("_", " ")


# --------------------------------------------------------------------------- rendering

_CSS = """
body{font-family:sans-serif;line-height:1.45;margin:0 auto;max-width:72rem;padding:1rem 2rem;color:#222}
h1{font-size:1.6rem;margin-bottom:.2rem}h2{font-size:1.25rem;border-bottom:1px solid #ccc;padding-top:.6rem}
nav ol{columns:2;font-size:.92rem}
.tablewrap{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;font-size:.85rem;margin:.6rem 0}
th,td{border:1px solid #ccc;padding:.2rem .45rem;text-align:left;vertical-align:top}
th{background:#f0f0f0}td.num{text-align:right;font-variant-numeric:tabular-nums}
tr.miss td{background:#fde2e1}tr.miss td:first-child{border-left:4px solid #c0392b}
.summary{font-weight:bold}.caption{font-size:.92rem;color:#333}
.comparison{border-left:4px solid #888;padding-left:.5rem;font-size:.92rem}
figure{margin:.6rem 0}figure img{max-width:100%;height:auto;border:1px solid #ddd}
code{font-size:.85rem;word-break:break-all}.dirty{color:#c0392b;font-weight:bold}
.muted{color:#666;font-size:.85rem}
"""


def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _paragraphs(text: str, cls: str = "") -> str:
    attr = f' class="{cls}"' if cls else ""
    return "".join(f"<p{attr}>{_e(p.strip())}</p>" for p in re.split(r"\n\s*\n", text) if p.strip())


def _is_number(text: str) -> bool:
    try:
        float(text)
    except (TypeError, ValueError):
        return False
    return True


def _cell(text: str) -> str:
    """A table cell: floats shown to 4 significant digits, the file's exact text in the tooltip."""
    if text is None:
        text = ""
    if _is_number(text) and re.search(r"[.eE]", text) and text.strip().lower() not in ("nan", "inf", "-inf"):
        value = float(text)
        shown = format(value, ".4g")
        if shown == text:
            return f'<td class="num">{_e(text)}</td>'
        return f'<td class="num" title="{_e(text)}">{_e(shown)}</td>'
    if _is_number(text):
        return f'<td class="num">{_e(text)}</td>'
    return f"<td>{_e(text)}</td>"


def read_table(path) -> tuple[list[str], list[list[str]]]:
    """Columns and rows (as the file's text) of a CSV, or of a JSON object flattened to key/value."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        with open(path) as fh:
            obj = json.load(fh)
        if isinstance(obj, list) and obj and all(isinstance(r, dict) for r in obj):
            cols = list(dict.fromkeys(k for r in obj for k in r))
            return cols, [[_json_text(r.get(c, "")) for c in cols] for r in obj]
        return ["quantity", "value"], [[k, _json_text(v)] for k, v in _flatten(obj)]
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        return [], []
    return rows[0], [r + [""] * (len(rows[0]) - len(r)) for r in rows[1:]]


def _json_text(v) -> str:
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (dict, list)):
        return json.dumps(v, sort_keys=True)
    return "" if v is None else str(v)


def _flatten(obj, prefix=""):
    if isinstance(obj, dict):
        for k in sorted(obj):
            yield from _flatten(obj[k], f"{prefix}{k}." if isinstance(obj[k], dict) else f"{prefix}{k}")
    else:
        yield prefix.rstrip("."), obj


_TRUE = {"true", "yes", "1", "ok", "pass"}
_FALSE = {"false", "no", "0", "fail"}


def table_summary(columns: list[str], rows: list[list[str]], highlight: Mapping | None = None) -> str:
    """One line computed from the table: row count, and how many are true in each boolean column."""
    bits = [f"{len(rows)} row{'s' if len(rows) != 1 else ''}"]
    for j, col in enumerate(columns):
        values = [r[j].strip().lower() for r in rows if j < len(r) and r[j].strip()]
        if values and all(v in _TRUE | _FALSE for v in values) and not all(_is_number(v) for v in values):
            n_true = sum(v in _TRUE for v in values)
            bits.append(f"{col}: {n_true} of {len(values)} true")
    if highlight:
        n = sum(1 for r in rows if _highlighted(columns, r, highlight))
        bits.append(f"{n} highlighted ({highlight['column']} = {highlight['equals']})")
    return "; ".join(bits)


def _highlighted(columns, row, highlight) -> bool:
    if not highlight or highlight.get("column") not in columns:
        return False
    j = columns.index(highlight["column"])
    return j < len(row) and row[j].strip() == str(highlight["equals"])


def _comparison_summary(columns, rows) -> str:
    """The paper-vs-reproduced headline, from the table itself."""
    if "within_10pct" not in columns:
        return ""
    j = columns.index("within_10pct")
    ok = sum(1 for r in rows if r[j].strip() == "True")
    return (f"{ok} of {len(rows)} comparisons agree with the paper within 10 % (or hold, for qualitative "
            f"statements); {len(rows) - ok} do not and are highlighted with the reason found.")


def figure_comparison(name: str, columns: list[str], rows: list[list[str]]) -> str:
    """This figure's rows of the paper-vs-reproduced table, summarised (empty if none)."""
    m = _FIG_NUMBER.match(name)
    if not m or "figure" not in columns or "within_10pct" not in columns:
        return ""
    n = int(m.group(1))
    jf, jw = columns.index("figure"), columns.index("within_10pct")
    jc = columns.index("case") if "case" in columns else None
    jq = columns.index("quantity") if "quantity" in columns else None
    js = columns.index("start") if "start" in columns else None
    mine = [r for r in rows if n in {int(x) for x in re.findall(r"\d+", re.sub(r"\([^)]*\)", "", r[jf]))}]
    if not mine:
        return ""
    misses = [r for r in mine if r[jw].strip() != "True"]
    text = f"Against the paper: {len(mine) - len(misses)} of {len(mine)} of this figure's reported values agree"
    if not misses:
        return text + "."

    def what(r):
        bits = [r[jc] if jc is not None else "", r[jq] if jq is not None else ""]
        if js is not None and r[js] not in ("", "-"):
            bits.append(f"start {r[js]}")
        return ", ".join(b for b in bits if b)

    return text + "; differing: " + "; ".join(what(r) for r in misses) + " (highlighted in the table)."


LONG_TABLE = 60  # rows; a longer table is folded under its summary line


def _render_table(columns, rows, highlight=None) -> str:
    head = "".join(f"<th scope=\"col\">{_e(c)}</th>" for c in columns)
    body = []
    for r in rows:
        cls = ' class="miss"' if _highlighted(columns, r, highlight) else ""
        body.append(f"<tr{cls}>" + "".join(_cell(v) for v in r) + "</tr>")
    table = (f'<div class="tablewrap"><table><thead><tr>{head}</tr></thead>'
             f"<tbody>{''.join(body)}</tbody></table></div>")
    if len(rows) > LONG_TABLE:
        return f"<details><summary>All {len(rows)} rows</summary>{table}</details>"
    return table


_MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".gif": "image/gif",
         ".svg": "image/svg+xml", ".webp": "image/webp"}


def _png_size(data: bytes):
    if data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR":
        return struct.unpack(">II", data[16:24])
    return None


def data_uri(path) -> tuple[str, tuple | None]:
    path = Path(path)
    data = path.read_bytes()
    mime = _MIME.get(path.suffix.lower())
    if mime is None:
        raise ValueError(f"{path}: not an image type the report can embed")
    if mime == "image/png" and _png_size(data) is None:
        raise ValueError(f"{path}: not a PNG file")
    return f"data:{mime};base64,{base64.b64encode(data).decode('ascii')}", _png_size(data)


def _section_list(sections) -> list[dict]:
    if isinstance(sections, Mapping):
        return [{"id": k, **v} for k, v in sections.items()]
    return [dict(s) for s in sections]


def _provenance_html(prov: Mapping) -> str:
    out = []
    dirty = str(prov.get("git_dirty", "unknown"))
    rows = [
        ("git commit", f"<code>{_e(prov.get('git_commit', 'unknown'))}</code>"),
        ("uncommitted changes", f'<span class="dirty">{_e(dirty)}</span>' if dirty != "no" else _e(dirty)),
        ("code version", _e(prov.get("code_version", "unknown"))),
        ("configuration sha256", f"<code>{_e(prov.get('config_sha256') or 'not given')}</code>"),
        ("executor", _e(prov.get("executor", "unknown"))),
        ("report generated", _e(prov.get("generated", ""))),
    ]
    out.append('<table class="kv" id="provenance-run"><tbody>' + "".join(
        f'<tr><th scope="row">{_e(k)}</th><td>{v}</td></tr>' for k, v in rows) + "</tbody></table>")
    packages = prov.get("packages") or {}
    if packages:
        out.append("<h3>Package versions</h3>")
        out.append('<table id="provenance-packages"><thead><tr><th scope="col">package</th>'
                   '<th scope="col">version</th></tr></thead><tbody>' + "".join(
                       f"<tr><td>{_e(k)}</td><td>{_e(v)}</td></tr>" for k, v in sorted(packages.items()))
                   + "</tbody></table>")
    bench = list(prov.get("benchmarks") or [])
    if bench:
        per_rule: dict[str, list[float]] = {}
        for b in bench:
            per_rule.setdefault(b["rule"], []).append(float(b["s"]))
        total = sum(sum(v) for v in per_rule.values())
        out.append("<h3>Run times (Snakemake benchmarks)</h3>")
        out.append(f'<p class="summary">{len(bench)} job{"s" if len(bench) != 1 else ""}, {total:.1f} s of '
                   "wall time in total (summed over jobs; jobs may have run in parallel).</p>")
        out.append('<table id="provenance-rules"><thead><tr><th scope="col">rule</th><th scope="col">jobs</th>'
                   '<th scope="col">total s</th><th scope="col">mean s</th><th scope="col">max s</th></tr>'
                   "</thead><tbody>" + "".join(
                       f'<tr><td>{_e(rule)}</td><td class="num">{len(v)}</td><td class="num">{sum(v):.2f}</td>'
                       f'<td class="num">{sum(v) / len(v):.2f}</td><td class="num">{max(v):.2f}</td></tr>'
                       for rule, v in sorted(per_rule.items())) + "</tbody></table>")
        out.append("<details><summary>Every job</summary>"
                   '<table id="provenance-jobs"><thead><tr><th scope="col">rule</th><th scope="col">job</th>'
                   '<th scope="col">s</th></tr></thead><tbody>' + "".join(
                       f'<tr><td>{_e(b["rule"])}</td><td>{_e(b["job"])}</td>'
                       f'<td class="num">{float(b["s"]):.2f}</td></tr>'
                       for b in sorted(bench, key=lambda b: (b["rule"], b["job"]))) + "</tbody></table></details>")
    return "".join(out)


def render_report(sections, provenance: Mapping | None, title: str = "Impact dampers: the reproduced study"
                  ) -> tuple[str, list[str]]:
    """The page's HTML (ASCII, characters beyond it as references) and the ids of the sections shown."""
    secs = _section_list(sections)
    comparison = None
    for s in secs:
        if s.get("comparison") or s.get("id") == "paper_vs_reproduced":
            p = s.get("path")
            if p and Path(p).is_file():
                comparison = read_table(p)
                break
    parts, toc, shown = [], [], []
    for s in secs:
        kind, sid = s.get("kind"), str(s.get("id", ""))
        if kind not in KINDS:
            raise ValueError(f"section {sid!r}: kind must be one of {KINDS}, not {kind!r}")
        if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_.:-]*", sid):
            raise ValueError(f"section id {sid!r} is not a valid HTML id")
        if sid in shown or sid == "provenance":
            raise ValueError(f"section id {sid!r} is used twice")
        stitle = s.get("title") or sid
        path = s.get("path")
        if kind in ("table", "figure"):
            if not path or not Path(path).is_file():
                log.info("report: section %s left out (no file %s)", sid, path)
                continue
        body = []
        if kind == "text":
            if s.get("html") is not None:
                body.append(str(s["html"]))
            elif s.get("text") is not None:
                body.append(_paragraphs(str(s["text"])))
            elif path and Path(path).is_file():
                body.append(_paragraphs(Path(path).read_text()))
            else:
                continue
        elif kind == "table":
            columns, rows = read_table(path)
            highlight = s.get("highlight")
            is_cmp = bool(s.get("comparison")) or sid == "paper_vs_reproduced"
            summary = _comparison_summary(columns, rows) if is_cmp else ""
            if not summary and Path(path).suffix.lower() != ".json":  # a JSON object is a list of values
                summary = table_summary(columns, rows, highlight)
            if summary:
                body.append(f'<p class="summary">{_e(summary)}</p>')
            if s.get("caption"):
                body.append(_paragraphs(s["caption"], "caption"))
            body.append(_render_table(columns, rows, highlight))
            body.append(f'<p class="muted">From <code>{_e(_display_path(path))}</code>.</p>')
        else:
            uri, size = data_uri(path)
            wh = f' width="{size[0]}" height="{size[1]}"' if size else ""
            cap = s.get("caption") or figure_caption(sid)
            extra = figure_comparison(Path(path).stem, *comparison) if comparison else ""
            body.append(f'<figure><img src="{uri}" alt="{_e(stitle)}"{wh}>'
                        f"<figcaption>{_paragraphs(cap, 'caption')}"
                        + (f'<p class="comparison">{_e(extra)}</p>' if extra else "")
                        + f'<p class="muted">From <code>{_e(_display_path(path))}</code>.</p>'
                        "</figcaption></figure>")
        parts.append(f'<section id="{_e(sid)}"><h2>{_e(stitle)}</h2>{"".join(body)}</section>')
        toc.append(f'<li><a href="#{_e(sid)}">{_e(stitle)}</a></li>')
        shown.append(sid)
    if provenance is not None:
        parts.append(f'<section id="provenance"><h2>Provenance of this run</h2>{_provenance_html(provenance)}'
                     "</section>")
        toc.append('<li><a href="#provenance">Provenance of this run</a></li>')
        shown.append("provenance")
    commit = (provenance or {}).get("git_commit", "")
    page = (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{_e(title)}</title>\n"
        '<link rel="icon" href="data:,">\n'
        f"<style>{_CSS}</style>\n</head>\n<body>\n"
        f"<header><h1>{_e(title)}</h1>"
        f'<p class="muted">Built from the result files of commit <code>{_e(commit or "unknown")}</code>; '
        "every number below is read from those files.</p></header>\n"
        f'<nav aria-label="Contents"><ol>{"".join(toc)}</ol></nav>\n<main>\n'
        + "\n".join(parts)
        + "\n</main>\n</body>\n</html>\n"
    )
    return page.encode("ascii", "xmlcharrefreplace").decode("ascii"), shown


def _display_path(path) -> str:
    """A result file's path from ``results/`` on, so the page names no machine-specific folder."""
    parts = Path(path).parts
    if "results" in parts:
        i = len(parts) - 1 - parts[::-1].index("results")
        return "/".join(parts[i:])
    return Path(path).name


def build_report(out_html, sections, provenance: Mapping | None) -> Path:
    """Write the report atomically; return its path.

    sections: ordered list of section dicts (or a dict id -> section); provenance: as
    ``collect_provenance`` returns it (None leaves the provenance section out).
    """
    page, shown = render_report(sections, provenance)
    out = Path(out_html)
    write_text_atomic(out, page)
    log.info("report %s: sections %s", out, ", ".join(shown))
    return out


# --------------------------------------------------------------------------- Snakemake glue


# a standard table that its rule keeps under a name of its own
STANDARD_STEMS = {"validation_table": "cross_validation"}


def snakemake_main(smk) -> Path:
    """Body of the ``report`` rule's script.

    Named inputs: ``shown``, what the workflow's registry says the report shows (images; CSV and
    JSON tables: one whose file stem, or its STANDARD_STEMS alias, is a standard section id takes
    that section's place, the others come last in their order); ``benchmarks`` (benchmark TSVs;
    default: every one under results/benchmarks); ``library`` is ignored.  ``resources.executor``
    (or ``params.executor``) names the executor.
    """
    inp = smk.input
    names = set(inp.keys()) if hasattr(inp, "keys") else set()

    def named(key):
        if key not in names:
            return []
        value = getattr(inp, key)
        return [str(value)] if isinstance(value, str) else [str(v) for v in value]

    shown = named("shown")
    figures = [p for p in shown if Path(p).suffix.lower() in _MIME]
    extra, tables = {}, []
    for path in shown:
        if path in figures:
            continue
        sid = STANDARD_STEMS.get(Path(path).stem, Path(path).stem)
        if sid in STANDARD_TABLES:
            extra[sid] = path
        else:
            tables.append(path)
    results = Path(smk.output[0]).parent.parent
    sections = standard_sections(results, figures=figures, extra=extra, config=smk.config, tables=tables)
    # only what the rule declares: standard files not wired as inputs stay out
    declared = {str(Path(p)) for p in shown}
    sections = [s for s in sections if s["kind"] == "text" or str(Path(s["path"])) in declared]
    bench = named("benchmarks")
    if not bench:
        bench_dir = getattr(smk.params, "benchmarks", None) if hasattr(smk, "params") else None
        bench = find_benchmarks(bench_dir or results / "benchmarks")
    executor = "unknown"
    for where in ("resources", "params"):  # the rule passes it as a resource (no rerun when it changes)
        value = getattr(getattr(smk, where, None), "executor", None)
        if isinstance(value, str) and value:
            executor = value
            break
    prov = collect_provenance(smk.config, executor=executor, benchmarks=bench)
    return build_report(smk.output[0], sections, prov)
