"""The study's HTML report: the data it shows, prepared from the result files only.

The page itself is a Jinja2 template (``workflow/report/index.html.j2``); its captions are the
workflow's caption files (``workflow/report/*.rst``, Jinja where a caption varies), the same ones
Snakemake's own report shows, and its overview is the workflow's description (``workflow.rst``).
This module reads the tables, embeds the figures as base64 data URIs, summarises what the data
says (row counts, agreement with the paper) and gathers the run's provenance; it holds no caption,
title or category of its own.  The page loads no external resource (no script, font, stylesheet
or CDN).

A section is a dict::

    {"path": "results/figures/fig08.png", "title": "Fig. 8: ...", "category": "2. The paper's figures",
     "caption": "workflow/report/figure.rst", "wildcards": {"fig": "fig08"}}

with ``path`` a PNG (a figure) or a CSV/JSON file (a table).  ``sections_from_registry`` takes
them in the form the workflow's registry gives (``report_sections()`` in targets.smk), where
``subcategory`` is the title.  A section whose file does not exist is left out.
"""

from __future__ import annotations

import base64
import collections
import csv
import hashlib
import io
import itertools
import json
import logging
import math
import re
from collections.abc import Iterable, Mapping
from pathlib import Path
from types import SimpleNamespace

import pandas as pd
from PIL import Image, UnidentifiedImageError

from impact import __version__
from impact.outputs.files import write_text_atomic
from impact.outputs.labels import cell_text, column_label, label
from impact.outputs.provenance import git_state, now_utc, package_versions

log = logging.getLogger(__name__)

# a figure whose file stem is figNN is the paper's Fig. NN: its rows of the comparison table apply
_FIG_NUMBER = re.compile(r"^fig0*(\d+)$")
# the column that marks a table as the paper-vs-reproduced comparison, and its rows as misses
AGREEMENT_COLUMN = "within_10pct"
LONG_TABLE = 60  # rows; a longer table is folded under its summary line


# --------------------------------------------------------------------------- captions (rst + Jinja)


def render_rst(text: str) -> dict:
    """reStructuredText as HTML parts: ``title`` (a lone top section's) and ``body``."""
    from docutils.core import publish_parts

    settings = {"report_level": 2, "halt_level": 3, "embed_stylesheet": False, "doctitle_xform": True}
    parts = publish_parts(text, writer="html5", settings_overrides=settings)
    return {"title": parts["title"], "body": parts["body"]}


def render_caption(path, wildcards: Mapping | None = None, config: Mapping | None = None) -> dict:
    """A caption file as Snakemake's report renders it: Jinja (``snakemake.wildcards``,
    ``snakemake.config``) first, then reStructuredText; includes resolve from the working folder."""
    from jinja2 import Environment, StrictUndefined

    env = Environment(trim_blocks=True, lstrip_blocks=True, undefined=StrictUndefined)
    smk = SimpleNamespace(wildcards=SimpleNamespace(**dict(wildcards or {})), config=dict(config or {}))
    return render_rst(env.from_string(Path(path).read_text(encoding="utf-8")).render(snakemake=smk))


def sections_from_registry(entries: Iterable[Mapping], config: Mapping | None = None) -> list[dict]:
    """The registry's entries as sections, their captions rendered, grouped by category.

    Categories keep the order of their names (they are numbered, as Snakemake's report sorts
    them); within one, the registry's order.
    """
    entries = list(entries)
    order = sorted(range(len(entries)), key=lambda i: (str(entries[i]["category"]), i))
    sections = []
    for i in order:
        e = entries[i]
        caption = render_caption(e["caption"], e.get("wildcards"), config) if e.get("caption") else None
        sections.append({"path": str(e["path"]), "title": e.get("subcategory") or Path(e["path"]).stem,
                         "category": e["category"], "caption_html": caption["body"] if caption else ""})
    return sections


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


def landing_page(overview, config, out) -> str:
    """The description Snakemake's report opens on (its ``report:``): the workflow's overview, then the run's
    provenance as labelled fields (commit, uncommitted changes, the configuration's hash, code version), the
    same values as the HTML report's.  Written to ``out``; returns its path.

    Not a ``--report-metadata`` file: Snakemake 9.27 renders each string value there into docutils' whole
    parts dictionary, so the page showed WHOLE / ENCODING / VERSION blocks instead of the fields.
    """
    state = git_state()
    fields = {"git commit": f"``{state['git_commit']}``", "uncommitted changes": state["git_dirty"],
              "configuration sha256": f"``{config_hash(config)}``", "code version": __version__}
    text = Path(overview).read_text(encoding="utf-8").rstrip("\n")
    text += "\n\nProvenance of this run\n----------------------\n\n"
    text += "".join(f":{name}: {value}\n" for name, value in fields.items())
    write_text_atomic(out, text)
    return str(Path(out).resolve())


# --------------------------------------------------------------------------- tables and figures


def html_id(name: str) -> str:
    """A valid, readable HTML id from a file's stem."""
    out = re.sub(r"[^A-Za-z0-9_.:-]+", "-", name).strip("-") or "section"
    return out if out[0].isalpha() else f"s-{out}"


def _is_number(text: str) -> bool:
    try:
        float(text)
    except (TypeError, ValueError):
        return False
    return True


def table_cell(text: str) -> dict:
    """A table cell as the template shows it: words for what the file writes as an identifier, a boolean or a
    missing value (outputs.labels), floats to 4 significant digits; the file's text kept beside."""
    text = "" if text is None else text
    number = _is_number(text) and text.strip().lower() not in ("nan", "inf", "-inf")
    shown = text
    if number and re.search(r"[.eE]", text):
        shown = format(float(text), ".4g")
    elif not number:
        shown = cell_text(text)
    return {"text": text, "shown": shown, "number": number}


def read_table(path) -> tuple[list[str], list[list[str]]]:
    """Columns and rows (as the file's text) of a CSV, or of a JSON object flattened to key/value."""
    path = Path(path)
    if path.suffix.lower() == ".json":
        with open(path) as fh:
            obj = json.load(fh)
        if isinstance(obj, list) and obj and all(isinstance(r, dict) for r in obj):
            cols = list(dict.fromkeys(k for r in obj for k in r))
            return cols, [[_json_text(r.get(c, "")) for c in cols] for r in obj]
        return ["quantity", "value"], [[_key_text(k), _json_text(v)] for k, v in _flatten(obj)]
    # every cell as the file writes it (no type guessed, no NaN made): the report shows what the file holds
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    return list(frame.columns), frame.values.tolist()


def _json_text(v) -> str:
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (dict, list)):
        return json.dumps(v, sort_keys=True)
    return "" if v is None else str(v)


def _flatten(obj, prefix=()):
    """(path of keys, value) of every leaf of a nested object."""
    if isinstance(obj, dict):
        for k in sorted(obj):
            yield from _flatten(obj[k], (*prefix, str(k)))
    else:
        yield prefix, obj


def _key_text(path: tuple) -> str:
    """A nested key as words: each level labelled, the levels joined by arrows."""
    return " › ".join(label(k).replace("_", " ").replace("lambda", "λ") for k in path)


_TRUE = {"true", "yes", "1", "ok", "pass"}
_FALSE = {"false", "no", "0", "fail"}


def table_summary(columns: list[str], rows: list[list[str]], highlight: Mapping | None = None) -> str:
    """One line computed from the table: row count, and how many are true in each boolean column."""
    bits = [f"{len(rows)} row{'s' if len(rows) != 1 else ''}"]
    for j, col in enumerate(columns):
        values = [r[j].strip().lower() for r in rows if j < len(r) and r[j].strip()]
        if values and all(v in _TRUE | _FALSE for v in values) and not all(_is_number(v) for v in values):
            n_true = sum(v in _TRUE for v in values)
            bits.append(f"{column_label(col)}: {n_true} of {len(values)} yes")
    if highlight:
        n = sum(1 for r in rows if _highlighted(columns, r, highlight))
        bits.append(f"{n} highlighted ({column_label(highlight['column'])}: {cell_text(highlight['equals'])})")
    return "; ".join(bits)


def _highlighted(columns, row, highlight) -> bool:
    if not highlight or highlight.get("column") not in columns:
        return False
    j = columns.index(highlight["column"])
    return j < len(row) and row[j].strip() == str(highlight["equals"])


def _comparison_summary(columns, rows) -> str:
    """The paper-vs-reproduced headline, from the table itself."""
    j = columns.index(AGREEMENT_COLUMN)
    ok = sum(1 for r in rows if r[j].strip() == "True")
    return (f"{ok} of {len(rows)} comparisons agree with the paper within 10 % (or hold, for qualitative "
            f"statements); {len(rows) - ok} do not and are highlighted with the reason found.")


#: the column of a table that names the best of several options per row (loads_best_damper.csv)
BEST_COLUMN = "best"


def _best_summary(columns, rows) -> str:
    """Which option a table finds best, and in how many of its rows: the table's finding, in one line."""
    j = columns.index(BEST_COLUMN)
    counts = collections.Counter(r[j].strip() for r in rows if j < len(r) and r[j].strip())
    return _ranked("The best", counts, f"{len(rows)} rows")


def _ranked(what: str, counts: collections.Counter, out_of: str) -> str:
    """'What: A in 5 of 9 cases, B in 3, C in 1.' from the counts, most first ('' when there are none)."""
    ranked = [f"{cell_text(name)} in {n}" for name, n in counts.most_common()]
    return f"{what}: {ranked[0]} of {out_of}" + "".join(f", {r}" for r in ranked[1:]) + "." if ranked else ""


def _largest_reduction_summary(columns, rows) -> str:
    """Which damper reduces the most, counted over the table's cases (every column but the damper and the
    measures): the finding of a verdict table with a median reduction per damper and case."""
    jd, jr = columns.index("damper"), columns.index("median_reduction")
    case_columns = [j for j, c in enumerate(columns) if c in ("building", "group", "mass_ratio", "load", "archetype")]
    best: dict[tuple, tuple[float, str]] = {}
    for r in rows:
        if _is_number(r[jr]) and math.isfinite(float(r[jr])):
            case = tuple(r[j] for j in case_columns)
            best[case] = max(best.get(case, (-math.inf, "")), (float(r[jr]), r[jd]))
    counts = collections.Counter(damper for _, damper in best.values())
    return _ranked("The largest median reduction", counts, f"{len(best)} cases")


def _worse_share_summary(columns, rows) -> str:
    """How often each damper makes a run worse, over all the table's runs: a helps/worse table's finding."""
    jd, jc, jw = columns.index("damper"), columns.index("cases"), columns.index("makes_worse")
    runs, worse = collections.Counter(), collections.Counter()
    for r in rows:
        if _is_number(r[jc]) and _is_number(r[jw]):
            runs[r[jd]] += int(float(r[jc]))
            worse[r[jd]] += int(float(r[jw]))
    shares = [f"{cell_text(d)} {100 * worse[d] / runs[d]:.0f} %" for d in runs if runs[d]]
    return f"Runs a damper makes worse (over 5 %), of all its runs and measures: {', '.join(shares)}." if shares else ""


#: what a table concludes, by the columns it has: (the columns, the finding), the first that fits is the table's
FINDINGS = (((BEST_COLUMN,), _best_summary), (("damper", "median_reduction"), _largest_reduction_summary),
            (("damper", "cases", "makes_worse"), _worse_share_summary))


def _finding(columns, rows) -> str:
    return next((found(columns, rows) for needs, found in FINDINGS if set(needs) <= set(columns)), "")


def figure_comparison(name: str, columns: list[str], rows: list[list[str]]) -> str:
    """This figure's rows of the paper-vs-reproduced table, summarised (empty if none)."""
    m = _FIG_NUMBER.match(name)
    if not m or "figure" not in columns or AGREEMENT_COLUMN not in columns:
        return ""
    n = int(m.group(1))
    jf, jw = columns.index("figure"), columns.index(AGREEMENT_COLUMN)
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


_MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".gif": "image/gif",
         ".svg": "image/svg+xml", ".webp": "image/webp"}


def _png_size(data: bytes):
    """(width, height) of a PNG, or None if the bytes are not one (Pillow reads only the header)."""
    try:
        with Image.open(io.BytesIO(data)) as image:
            return image.size if image.format == "PNG" else None
    except (UnidentifiedImageError, OSError):
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


def _table_view(path: Path) -> dict:
    columns, rows = read_table(path)
    highlight = {"column": AGREEMENT_COLUMN, "equals": "False"} if AGREEMENT_COLUMN in columns else None
    # a finding: what the table concludes, which the page also lists at its top
    finding = _comparison_summary(columns, rows) if highlight else _finding(columns, rows)
    summary = finding
    if not summary and path.suffix.lower() != ".json":  # a JSON object is a list of values, not rows
        summary = table_summary(columns, rows, highlight)
    # the page's own table (not DataFrame.to_html): it highlights the rows that miss the paper, folds a long
    # table and shows each cell in words with the file's text kept as its tooltip
    return {"kind": "table", "columns": [{"id": c, "label": column_label(c)} for c in columns], "summary": summary,
            "finding": finding,
            "folded": len(rows) > LONG_TABLE,
            "rows": [{"miss": _highlighted(columns, r, highlight), "cells": [table_cell(v) for v in r]}
                     for r in rows]}


def _figure_view(path: Path, comparison) -> dict:
    uri, size = data_uri(path)
    return {"kind": "figure", "uri": uri, "size": size,
            "comparison": figure_comparison(path.stem, *comparison) if comparison else ""}


def _comparison_table(sections) -> tuple | None:
    for s in sections:
        path = Path(s["path"])
        if path.suffix.lower() == ".csv" and path.is_file():
            columns, rows = read_table(path)
            if AGREEMENT_COLUMN in columns and "figure" in columns:
                return columns, rows
    return None


def section_views(sections: Iterable[Mapping]) -> list[dict]:
    """What the template shows of each section whose file exists: a table's cells and summary, a
    figure's data URI and its agreement with the paper."""
    sections = [dict(s) for s in sections]
    comparison = _comparison_table(sections)
    views, ids = [], set()
    for s in sections:
        path = Path(s["path"])
        if not path.is_file():
            log.info("report: %s left out (no file)", path)
            continue
        if path.suffix.lower() in _MIME:
            view = _figure_view(path, comparison)
        elif path.suffix.lower() in (".csv", ".json"):
            view = _table_view(path)
        else:
            raise ValueError(f"{path}: the report shows figures ({', '.join(_MIME)}) and tables (.csv, .json)")
        sid = html_id(path.stem)
        if sid in ids or sid == "provenance":
            raise ValueError(f"{path}: section id {sid!r} is used twice")
        ids.add(sid)
        views.append({**s, **view, "id": sid, "source": _display_path(path)})
    return views


def _display_path(path) -> str:
    """A result file's path from ``results/`` on, so the page names no machine-specific folder."""
    parts = Path(path).parts
    if "results" in parts:
        i = len(parts) - 1 - parts[::-1].index("results")
        return "/".join(parts[i:])
    return Path(path).name


# --------------------------------------------------------------------------- the page


def provenance_view(prov: Mapping) -> dict:
    """The provenance as the template shows it, with the run times summed per rule."""
    bench = sorted(prov.get("benchmarks") or [], key=lambda b: (b["rule"], b["job"]))
    per_rule = [{"rule": rule, "seconds": [float(b["s"]) for b in jobs]}
                for rule, jobs in itertools.groupby(bench, key=lambda b: b["rule"])]
    for r in per_rule:
        s = r.pop("seconds")
        r.update(jobs=len(s), total=sum(s), mean=sum(s) / len(s), max=max(s))
    return {**prov, "jobs": bench, "per_rule": per_rule, "total_seconds": sum(r["total"] for r in per_rule)}


def render_report(sections, provenance: Mapping | None, template, overview: Mapping | None = None
                  ) -> tuple[str, list[str]]:
    """The page's HTML (ASCII, characters beyond it as references) and the ids of the sections shown.

    sections: as ``sections_from_registry`` gives them; template: the Jinja2 page template;
    overview: ``render_caption`` of the workflow's description (its title heads the page).
    """
    from jinja2 import Environment, FileSystemLoader, StrictUndefined, select_autoescape

    template = Path(template)
    env = Environment(loader=FileSystemLoader(template.parent), autoescape=select_autoescape(default=True),
                      undefined=StrictUndefined, trim_blocks=True, lstrip_blocks=True)
    views = section_views(sections)
    groups = [{"name": name, "sections": list(group)}
              for name, group in itertools.groupby(views, key=lambda v: v.get("category") or "Other results")]
    page = env.get_template(template.name).render(
        title=(overview or {}).get("title") or "Impact dampers: the reproduced study",
        overview=(overview or {}).get("body", ""), groups=groups, findings=[v for v in views if v.get("finding")],
        provenance=provenance_view(provenance) if provenance is not None else None)
    shown = [v["id"] for v in views] + (["provenance"] if provenance is not None else [])
    return page.encode("ascii", "xmlcharrefreplace").decode("ascii"), shown


def build_report(out_html, sections, provenance: Mapping | None, template, overview: Mapping | None = None
                 ) -> Path:
    """Write the report atomically; return its path (arguments as ``render_report``)."""
    page, shown = render_report(sections, provenance, template, overview)
    out = Path(out_html)
    write_text_atomic(out, page)
    log.info("report %s: sections %s", out, ", ".join(shown))
    return out


# --------------------------------------------------------------------------- Snakemake glue


def snakemake_main(smk) -> Path:
    """Body of the ``report`` rule's script.

    params.sections: the registry's entries (targets.smk ``report_sections()``); input.template and
    input.overview: the page template and the workflow's description; input.benchmarks: every
    registered job's benchmark; resources.executor: the executor's name.
    """
    sections = sections_from_registry(smk.params.sections, smk.config)
    overview = render_caption(smk.input.overview, config=smk.config)
    executor = getattr(smk.resources, "executor", None) or "unknown"
    prov = collect_provenance(smk.config, executor=executor, benchmarks=list(smk.input.benchmarks))
    return build_report(smk.output[0], sections, prov, smk.input.template, overview)
