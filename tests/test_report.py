"""The HTML report: built from a synthetic results tree, checked as HTML and in headless Chromium."""

from __future__ import annotations

import csv
import hashlib
import html
import json
import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import pytest
import yaml
from reference import HANG_GUARD_S
from snakemake.utils import validate

from impact.outputs import report

ROOT = Path(__file__).resolve().parents[1]
CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if os.access("/usr/bin/chromium", os.X_OK) else None)


def _study_config(**overrides) -> dict:
    """The study's configuration as every rule sees it (validated, the schema's defaults filled in: captions rely
    on them), with this test's sections in place of the study's."""
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text(encoding="utf-8"))
    validate(config, str(ROOT / "workflow" / "schemas" / "config.schema.yaml"))
    return config | overrides


CONFIG = _study_config(
    structure={"beta": 0.0048, "force_ratio": 0.096},
    protocol={"periods": 40, "average_from": 20, "freq": {"min": 0.96, "max": 1.04, "step": 0.04},
              "gap": {"min": 0.6, "max": 1.8, "step": 0.6}, "starts": {"cid": ["centre", "left"]}},
    figures={"fig08": {}, "fig99": {}})  # synthetic figures: the report takes any

PVR_ROWS = [
    # figure, case, quantity, start, paper, reproduced, rel_difference, within_10pct, g_optimum, reason
    ["8(a), 9(a)", "CID mu=0.01 e=0.25", "X_m at optimum g", "centre", "0.32", "0.4353203017068163",
     "0.36037594283380087", "False", "1.4", "initial condition matters: start 'left' gives 0.314 <&>"],
    ["8(a), 9(a)", "CID mu=0.01 e=0.25", "X_m at optimum g", "left", "0.32", "0.31393093404727745",
     "-0.018965831102257975", "True", "1.6", ""],
    ["9(b-d)", "PID mu=0.01 r'=0.5, e=0.25/0.45/0.65", "X_m at optimum rises with e", "centre", "yes", "yes",
     "", "True", "", ""],
    ["11", "TMD mu=0.01 beta=0.0048", "optimum f", "-", "0.99", "0.9894015886850624",
     "-0.0006044558736742842", "True", "", ""],
    ["11", "efficiency order", "TMD > CID > PID", "centre", "yes", "no (X_m TMD 0.122, CID 0.435)", "",
     "False", "", "order differs for this start"],
]
PVR_COLUMNS = ["figure", "case", "quantity", "start", "paper", "reproduced", "rel_difference", "within_10pct",
               "g_optimum", "reason"]


def _png(path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(3, 2))
    ax.plot([0, 1, 2], [1.0, 0.4, 0.6], "o-")
    ax.set_title(title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=60)
    plt.close(fig)


def _csv(path: Path, columns, rows) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(columns)
        w.writerows(rows)


@pytest.fixture
def results(tmp_path) -> Path:
    res = tmp_path / "results"
    _png(res / "figures" / "fig08.png", "fig08")
    _png(res / "figures" / "fig99.png", "fig99")
    _png(res / "figures" / "numerics_error_runtime.png", "numerics")
    _csv(res / "tables" / "paper_vs_reproduced.csv", PVR_COLUMNS, PVR_ROWS)
    _csv(res / "tables" / "masri_check.csv", ["mu", "e", "r", "ours", "masri", "agrees"],
         [["0.01", "0.5", "1.0", "0.4012", "0.4011", "True"], ["0.01", "0.5", "1.05", "0.52", "0.61", "False"],
          ["0.03", "0.5", "1.0", "0.3", "0.3", "True"]])
    (res / "tables" / "tmd_optimum.json").write_text(json.dumps(
        {"f": 0.9894, "beta_t": 0.0617, "X_m": 0.1218, "den_hartog": {"f": 0.990099, "beta_t": 0.06033}}))
    bench = res / "benchmarks"
    (bench / "figure").mkdir(parents=True)
    (bench / "sweep_curve").mkdir(parents=True)
    header = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"
    (bench / "figure" / "fig08.tsv").write_text(header + "3.15\t0:00:03\t208\t454\t141\t174\t0\t0.2\t79\t3.0\n")
    (bench / "sweep_curve" / "cid_mu0.01_e0.25.tsv").write_text(
        header + "10.0\t0:00:10\t1\t1\t1\t1\t0\t0\t1\t1\n" + "12.0\t0:00:12\t1\t1\t1\t1\t0\t0\t1\t1\n")
    (bench / "tmd_optimum.tsv").write_text(header + "0.50\t0:00:00\t1\t1\t1\t1\t0\t0\t1\t1\n")
    return res


REPORT = ROOT / "workflow" / "report"
TEMPLATE = REPORT / "index.html.j2"


def _entries(results: Path) -> list[dict]:
    """Sections as the workflow's registry gives them (targets.smk report_sections()), in its order."""
    def entry(path, caption, category, title, **wildcards):
        return {"path": str(results / path), "caption": str(REPORT / f"{caption}.rst"), "category": category,
                "subcategory": title, "wildcards": wildcards}

    return [
        entry("tables/tmd_optimum.json", "tmd_optimum", "2. Figures", "TMD optimum"),
        entry("figures/fig08.png", "figure", "2. Figures", "Fig. 8", fig="fig08"),
        entry("figures/fig99.png", "figure", "2. Figures", "Fig. 99", fig="fig99"),
        entry("tables/paper_vs_reproduced.csv", "paper_vs_reproduced", "1. Paper", "Paper vs ours"),
        entry("tables/masri_check.csv", "masri_check", "4. Masri", "Point by point"),
        entry("tables/cross_validation.csv", "cross_validation", "3. Experiment", "Not built in this tree"),
        entry("figures/numerics_error_runtime.png", "numerics_error_runtime", "6. Numerics", "Error"),
    ]


def _build(results: Path, **kw) -> tuple[Path, str, dict]:
    sections = report.sections_from_registry(_entries(results), CONFIG)
    prov = report.collect_provenance(CONFIG, executor="local-test", benchmarks=results / "benchmarks")
    overview = report.render_caption(REPORT / "workflow.rst", config=CONFIG)
    out = report.build_report(results / "report" / "index.html", sections, prov, TEMPLATE, overview)
    return out, out.read_text(encoding="ascii"), prov


class _Checker(HTMLParser):
    """Well-formedness beyond what browsers forgive: balanced tags, unique ids, resolvable anchors."""

    VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack, self.errors, self.ids, self.links, self.resources = [], [], [], [], []
        self.doctype = None
        self.imgs = []
        self.text = []

    def handle_decl(self, decl):
        self.doctype = decl

    def handle_starttag(self, tag, attrs):
        names = [k for k, _ in attrs]
        if len(names) != len(set(names)):
            self.errors.append(f"duplicate attribute in <{tag}>")
        a = dict(attrs)
        if "id" in a:
            self.ids.append(a["id"])
        if tag == "a" and "href" in a:
            self.links.append(a["href"])
        for key in ("src", "href", "srcset", "poster", "data"):
            if key in a and not (tag == "a" and key == "href"):
                self.resources.append(a[key])
        if tag == "img":
            self.imgs.append(a)
        if tag in {"script", "iframe", "object", "embed", "base"}:
            self.errors.append(f"<{tag}> in a report that needs none")
        if tag not in self.VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in self.VOID:
            self.stack.pop()

    def handle_endtag(self, tag):
        if tag in self.VOID:
            self.errors.append(f"end tag for void <{tag}>")
        elif not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else None}>")
        else:
            self.stack.pop()

    def handle_data(self, data):
        self.text.append(data)


def _check(page: str) -> _Checker:
    c = _Checker()
    c.feed(page)
    c.close()
    return c


@pytest.fixture(autouse=True)
def _in_the_repository(monkeypatch):
    """Captions include one another by path from the working folder, as in Snakemake's report."""
    monkeypatch.chdir(ROOT)


def test_report_shows_every_given_section_from_the_files(results):
    out, page, prov = _build(results)
    assert out == results / "report" / "index.html"
    ids = re.findall(r'<section id="([^"]+)"', page)
    # grouped by category, in the order of their numbered names; the registry's order within one
    assert ids == ["overview", "paper_vs_reproduced", "tmd_optimum", "fig08", "fig99", "masri_check",
                   "numerics_error_runtime", "provenance"]
    assert re.findall(r"<h2>([^<]+)</h2>", page) == ["What it finds", "The study", "1. Paper", "2. Figures", "4. Masri",
                                                     "6. Numerics", "Provenance of this run"]
    # files that do not exist give no section
    assert 'id="cross_validation"' not in page and "Not built in this tree" not in page
    # the comparison: rows not within 10 % are highlighted, with their reason (escaped)
    assert page.count('<tr class="miss">') == 2
    assert "initial condition matters: start &#39;left&#39; gives 0.314 &lt;&amp;&gt;" in page
    assert "order differs for this start" in page
    assert "3 of 5 comparisons agree with the paper within 10 %" in page
    # every number of the file is in the page: shown rounded, exact in the tooltip
    assert 'title="0.4353203017068163">0.4353</td>' in page
    # figures: embedded PNGs; captions from the workflow's caption files, with their Jinja applied
    assert page.count('src="data:image/png;base64,') == 3
    assert "The paper reads X_m = 0.32 at the optimum gap" in page  # fig08.rst, included by figure.rst
    assert "Figure fig99 of the study" in page and "figures: fig99</span>" in page
    assert "Against the paper: 1 of 2 of this figure&#39;s reported values agree" in page
    # closed-form check: rendered with a summary line computed from the table
    assert "3 rows; agrees: 2 of 3 yes" in page
    # the overview is the workflow's description, with this run's protocol from the configuration
    assert "<h1>Impact dampers for civil structures: a reproducible study</h1>" in page
    assert "40 natural periods per run, amplitude from period\n20 on" in page


def test_every_caption_file_renders_without_a_docutils_warning():
    wildcards = {"figure": {"fig": "fig08"}, "coexistence_figure": {"curve": "cid_mu0.01_e0.25"},
                 "hysteresis_figure": {"curve": "cid_mu0.01_e0.25"}}
    for path in sorted(REPORT.glob("*.rst")):
        # halt_level 3: an rst error (a broken include, bad markup) raises instead of printing into the page
        body = report.render_caption(path, wildcards.get(path.stem), CONFIG)["body"]
        assert len(body) > 100 and "System Message" not in body, path.name
    assert "Coexisting steady states of cid_mu0.01_e0.25" in report.render_caption(
        REPORT / "coexistence_figure.rst", wildcards["coexistence_figure"])["body"]


def test_provenance_section(results):
    _, page, prov = _build(results)
    canonical = json.dumps(CONFIG, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    assert prov["config_sha256"] == hashlib.sha256(canonical.encode()).hexdigest()
    assert prov["config_sha256"] in page
    assert prov["git_commit"] in page and prov["git_dirty"] in ("yes", "no", "unknown")
    assert "local-test" in page
    for name, version in prov["packages"].items():
        assert f"<td>{name}</td><td>{version}</td>" in page
    bench = {(b["rule"], b["job"]): b for b in prov["benchmarks"]}
    assert set(bench) == {("figure", "fig08"), ("sweep_curve", "cid_mu0.01_e0.25"), ("tmd_optimum", "")}
    assert bench[("sweep_curve", "cid_mu0.01_e0.25")]["s"] == pytest.approx(11.0)  # mean of the repeats
    assert bench[("sweep_curve", "cid_mu0.01_e0.25")]["repeats"] == 2
    assert "3 jobs, 14.7 s of wall time in total" in page
    assert '<tr><td>figure</td><td class="num">1</td><td class="num">3.15</td>' in page


def test_report_is_valid_self_contained_html(results):
    out, page, _ = _build(results)
    assert page.isascii()  # non-ASCII characters as references: no encoding can garble it
    c = _check(page)
    assert c.doctype == "DOCTYPE html"
    assert not c.errors, c.errors
    assert not c.stack, f"unclosed: {c.stack}"
    assert len(c.ids) == len(set(c.ids)), "duplicate ids"
    assert all(h.startswith("#") and h[1:] in c.ids for h in c.links), c.links
    # nothing to fetch: every resource is inline
    assert c.resources and all(r.startswith("data:") for r in c.resources), c.resources
    assert not re.search(r"(?i)(https?:)?//[a-z0-9.-]+\.[a-z]{2,}/", page.replace("citation-file-format", ""))
    assert "@import" not in page and "url(" not in page
    for img in c.imgs:
        assert img.get("alt") and int(img["width"]) > 0 and int(img["height"]) > 0
    # written atomically: no temporary file left beside it
    assert sorted(p.name for p in out.parent.iterdir()) == ["index.html"]


def test_only_figures_and_tables_and_nothing_half_written(tmp_path, results):
    (tmp_path / "notes.txt").write_text("x")
    sections = [{"path": str(tmp_path / "notes.txt"), "title": "Notes", "category": "1", "caption_html": ""}]
    with pytest.raises(ValueError, match="figures .* and tables"):
        report.build_report(tmp_path / "x.html", sections, None, TEMPLATE)
    assert not (tmp_path / "x.html").exists()
    twice = [{"path": str(results / "figures" / "fig08.png"), "title": t, "category": "1", "caption_html": ""}
             for t in ("a", "b")]
    with pytest.raises(ValueError, match="used twice"):
        report.build_report(tmp_path / "x.html", twice, None, TEMPLATE)
    out = report.build_report(tmp_path / "r" / "index.html", twice[:1], None, TEMPLATE)
    assert "provenance" not in out.read_text() and "<h1>Impact dampers: the reproduced study</h1>" in out.read_text()


# --------------------------------------------------------------------------- headless Chromium

_SELFTEST = """
<script>
(function () {
  var errors = [];
  window.addEventListener("error", function (ev) {
    var t = ev.target;
    errors.push(t && t !== window ? "resource failed: " + (t.src || t.href || t.tagName) : "error: " + ev.message);
  }, true);
  document.addEventListener("securitypolicyviolation", function (ev) {
    errors.push("blocked external resource: " + ev.blockedURI);
  });
  ["error", "warn"].forEach(function (level) {
    var orig = console[level];
    console[level] = function () {
      errors.push(level + ": " + Array.prototype.join.call(arguments, " "));
      orig.apply(console, arguments);
    };
  });
  window.addEventListener("load", function () {
    var imgs = Array.prototype.map.call(document.images, function (im) {
      return {alt: im.alt, complete: im.complete, naturalWidth: im.naturalWidth, naturalHeight: im.naturalHeight};
    });
    var out = document.createElement("pre");
    out.id = "selftest";
    out.textContent = JSON.stringify({errors: errors, images: imgs, title: document.title,
                                      sections: document.querySelectorAll("section").length});
    document.body.appendChild(out);
  });
})();
</script>
"""
# a strict policy on the tested copy: anything not inline is blocked and reported
_CSP = ('<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; img-src data:; '
        'style-src \'unsafe-inline\'; script-src \'unsafe-inline\'">')


def _chromium(args, user_dir: Path) -> subprocess.CompletedProcess:
    cmd = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           "--disable-dev-shm-usage", f"--user-data-dir={user_dir}", "--enable-logging=stderr", "--v=0",
           "--virtual-time-budget=5000", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=HANG_GUARD_S)


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium; `make test` "
                                             "installs it when run as root)")
def test_report_loads_in_headless_chromium_without_errors(results, tmp_path):
    out, page, _ = _build(results)
    n_figures = page.count('src="data:image/png;base64,')
    # the report itself carries no script: the self-test goes into a copy
    probe = tmp_path / "probe.html"
    probe.write_text(page.replace("<head>\n", "<head>\n" + _CSP + "\n", 1)
                     .replace("</body>", _SELFTEST + "</body>", 1), encoding="ascii")
    proc = _chromium(["--dump-dom", probe.as_uri()], tmp_path / "chromium-profile-1")
    assert proc.returncode == 0, proc.stderr[-3000:]
    m = re.search(r'<pre id="selftest">(.*?)</pre>', proc.stdout, re.S)
    assert m, f"self-test did not run:\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}"
    result = json.loads(html.unescape(m.group(1)))
    assert result["errors"] == []
    assert result["title"] == "Impact dampers for civil structures: a reproducible study"
    assert result["sections"] == 8
    assert len(result["images"]) == n_figures == 3
    for img in result["images"]:
        assert img["complete"] and img["naturalWidth"] > 0 and img["naturalHeight"] > 0, img
    # whatever reached the browser's console (none expected: the page has no script of its own)
    console = [ln for ln in proc.stderr.splitlines() if ":CONSOLE" in ln]
    assert console == [], console

    # control: the same probe does see a broken image, an external resource and a console error
    bad = page.replace("</main>", '<img alt="broken" src="data:image/png;base64,AAAA">'
                       '<img alt="external" src="https://example.invalid/x.png"></main>', 1)
    bad = bad.replace("<head>\n", "<head>\n" + _CSP + "\n", 1).replace(
        "</body>", _SELFTEST + "<script>console.error('control');</script></body>", 1)
    control = tmp_path / "control.html"
    control.write_text(bad, encoding="ascii")
    proc = _chromium(["--dump-dom", control.as_uri()], tmp_path / "chromium-profile-3")
    seen = json.loads(html.unescape(re.search(r'<pre id="selftest">(.*?)</pre>', proc.stdout, re.S).group(1)))
    assert any("blocked external resource" in e for e in seen["errors"]), seen["errors"]
    assert any("resource failed" in e for e in seen["errors"]), seen["errors"]
    assert any("control" in e for e in seen["errors"]), seen["errors"]
    assert [im["naturalWidth"] for im in seen["images"] if im["alt"] in ("broken", "external")] == [0, 0]

    # the unmodified report, as a reader sees it
    shot = tmp_path / "report.png"
    proc = _chromium([f"--screenshot={shot}", "--window-size=1280,2000", "--hide-scrollbars", out.as_uri()],
                     tmp_path / "chromium-profile-2")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert [ln for ln in proc.stderr.splitlines() if ":CONSOLE" in ln] == []
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert report._png_size(data) == (1280, 2000)


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium; `make test` "
                                             "installs it when run as root)")
@pytest.mark.parametrize("section", ["loads", "ida_s3_T0.5"])
def test_a_screenshot_shows_its_section_even_with_a_dot_in_its_id(section, tmp_path):
    """make screenshots shows each section alone: one whose id holds a dot (the IDA's, coexistence's) too."""
    sys.path.insert(0, str(ROOT / "tools"))
    from screenshots import alone_page

    page = ("<html><head><title>t</title></head><body><header>h</header><main>"
            '<section id="loads"><h2>a</h2><p>loads</p></section>'
            '<section id="ida_s3_T0.5"><h2>b</h2><p>ida</p></section></main>'
            "<pre id=\"shown\"></pre><script>document.getElementById('shown').textContent = "
            "[...document.querySelectorAll('section')].filter(s => getComputedStyle(s).display !== 'none')"
            ".map(s => s.id).join(',');</script></body></html>")
    probe = tmp_path / "alone.html"
    probe.write_text(alone_page(page, section), encoding="ascii")
    proc = _chromium(["--dump-dom", probe.as_uri()], tmp_path / "chromium-profile")
    assert re.search(r'<pre id="shown">(.*?)</pre>', proc.stdout).group(1) == section


class _Named(dict):
    """Stands in for Snakemake's named lists: keys() and attribute access."""

    def __getattr__(self, key):
        try:
            return self[key]
        except KeyError:
            raise AttributeError(key) from None


def test_snakemake_script_entry_shows_the_registry_sections(results):
    from types import SimpleNamespace

    entries = _entries(results)[:2]
    smk = SimpleNamespace(
        input=_Named(shown=[e["path"] for e in entries], overview=str(REPORT / "workflow.rst"), template=str(TEMPLATE),
                     benchmarks=[str(results / "benchmarks" / "figure" / "fig08.tsv")]),
        output=[str(results / "report" / "index.html")],
        params=_Named(sections=entries), resources=_Named(executor="slurm"), config=CONFIG)
    page = report.snakemake_main(smk).read_text()
    # masri_check.csv etc. exist but are not in the registry's sections: left out
    assert re.findall(r'<section id="([^"]+)"', page) == ["overview", "tmd_optimum", "fig08", "provenance"]
    assert '<th scope="row">executor</th><td>slurm</td>' in page
    assert "1 job, 3.1 s of wall time in total" in page


def test_long_tables_fold(tmp_path, results):
    rows = [[str(i), "True" if i % 3 else "False"] for i in range(report.LONG_TABLE + 1)]
    _csv(tmp_path / "long.csv", ["i", "ok"], rows)
    sections = [{"path": str(tmp_path / "long.csv"), "title": "Long", "category": "1", "caption_html": ""}]
    page, shown = report.render_report(sections, None, TEMPLATE)
    assert shown == ["long"]
    assert f"<details><summary>All {report.LONG_TABLE + 1} rows</summary>" in page
    assert f"{report.LONG_TABLE + 1} rows; ok: 40 of 61 yes" in page


def test_the_page_states_its_findings_first(tmp_path):
    """A new user found a long table of contents at the top and no finding: the tables that conclude something
    (against the paper, which damper is best) are listed first, each with its conclusion and a link."""
    _csv(tmp_path / "loads_best_damper.csv", ["building", "best"],
         [["s1_T0.5", "tmd"], ["s3_T1", "tmd"], ["s5_T2", "pid"]])
    _csv(tmp_path / "plain.csv", ["i", "x"], [["1", "2"]])
    sections = [{"path": str(tmp_path / name), "title": title, "category": "1", "caption_html": ""}
                for name, title in (("plain.csv", "Plain"), ("loads_best_damper.csv", "Best damper"))]
    page, _ = report.render_report(sections, None, TEMPLATE)
    top = page[: page.index('<nav aria-label="Contents">')]
    assert '<a href="#loads_best_damper">Best damper</a>: The best: TMD in 2 of 3 rows, PID in 1.' in top
    assert "Plain" not in top


def test_verdict_tables_state_what_they_conclude(tmp_path):
    """The IDA's verdicts: which damper reduces the median drift most, counted per case; the loads' verdicts: how
    often each damper makes a run worse.  Counted from the rows, never typed."""
    _csv(tmp_path / "ida.csv", ["building", "damper", "mass_ratio", "group", "median_reduction"],
         [["s1", "cid", "0.02", "far", "0.05"], ["s1", "tmd", "0.02", "far", "0.2"],
          ["s1", "cid", "0.02", "near", "0.3"], ["s1", "tmd", "0.02", "near", "0.1"],
          ["s3", "cid", "0.02", "far", "nan"], ["s3", "tmd", "0.02", "far", "0.1"]])
    _csv(tmp_path / "loads.csv", ["damper", "cases", "makes_worse"],
         [["cid", "100", "10"], ["cid", "100", "0"], ["tmd", "50", "1"]])
    assert report._table_view(tmp_path / "ida.csv")["finding"] == (
        "The largest median reduction: TMD in 2 of 3 cases, CID in 1.")
    assert report._table_view(tmp_path / "loads.csv")["finding"] == (
        "Runs a damper makes worse (over 5 %), of all its runs and measures: CID 5 %, TMD 2 %.")


# --------------------------------------------------------------------------- words for identifiers


@pytest.mark.parametrize("identifier, words", [
    ("cid_mu0.01_e0.25", "CID, μ = 0.01, e = 0.25"),
    ("pid_mu0.03_e0.45_rp1.5", "PID, μ = 0.03, e = 0.45, r' = 1.5"),
    ("cid_mu0.01_e0.25_nu0.2_f1.5_L0.01", "CID, μ = 0.01, e = 0.25, ν = 0.2 (1.5 Hz, 1 cm)"),
    ("s3_T0.5", "3 storeys, T1 = 0.5 s"), ("s1_T2", "1 storey, T1 = 2 s"),
    ("mu0.0252_d20_rp1_steel", "μ = 0.0252, d = 20 mm, r' = 1, steel wall"),
    ("pid_rp1_centre", "PID r' = 1, centre start"), ("cid_left", "CID, left start"),
    ("ivp_RK45", "solve_ivp RK45"), ("moreau_jean", "Moreau–Jean time stepping"), ("tmd", "TMD"),
    ("cid_2eipc", "CID on its 2-EIPC orbit (g = 1.6, left start)"), ("a plain phrase", "a plain phrase"),
    ("peak_roof", "peak roof displacement"), ("peak_drift", "peak inter-storey drift"),
])
def test_identifiers_are_shown_as_words(identifier, words):
    from impact.outputs.labels import label

    assert label(identifier) == words


def test_a_loads_run_is_named_in_words_with_its_pga_unit():
    """Not 'building s5_T0.5, record elcentro, intensity 0.5' (a new user's finding): words, and the PGA in g."""
    from impact.outputs.labels import load_case

    assert load_case({"building": "s5_T0.5", "record": "elcentro", "intensity": 0.5}) == (
        "5 storeys, T1 = 0.5 s, record elcentro, PGA 0.5 g")
    assert load_case({"building": "s5_T2", "wind_seed": 3}) == "5 storeys, T1 = 2 s, wind seed 3"


def test_a_table_shows_words_numbers_and_dashes_keeping_the_files_text(tmp_path):
    """Columns by their labels, identifiers as words, booleans as yes/no, NaN as a dash; the file's own text stays
    in the cell's tooltip, so nothing is lost."""
    path = tmp_path / "t.csv"
    path.write_text("curve,within_10pct,rel_difference,reason\ncid_mu0.01_e0.25,False,nan,grid edge\n")
    view = report._table_view(path)
    assert [c["label"] for c in view["columns"]] == ["curve", "within 10 %", "relative difference", "reason"]
    shown = [c["shown"] for c in view["rows"][0]["cells"]]
    assert shown == ["CID, μ = 0.01, e = 0.25", "no", "–", "grid edge"]
    assert view["rows"][0]["cells"][0]["text"] == "cid_mu0.01_e0.25"


def test_a_nested_summary_reads_as_words():
    keys = [report._key_text(k) for k, _ in report._flatten({"limits": {"centre": {"by_eigenvalue": {"max|lambda| in [0.0, 0.95)": {"landed": 3}}}}})]
    assert keys == ["limits › centre › by eigenvalue › max|λ| in [0.0, 0.95) › landed"]


# --------------------------------------------------------------------------- figures


def test_a_curve_lying_on_another_joins_its_legend_entry():
    """Fig. 10's friction curves that coincide were each listed in the legend, with only one visible: a curve
    within SAME_CURVE of one drawn before it is named in that one's entry instead."""
    import matplotlib.pyplot as plt
    import numpy as np
    import xarray as xr

    from impact.outputs import plotting

    def sweep(xm):
        g = np.array([0.5, 1.0, 1.5])
        return xr.Dataset({"X_m": (("start", "gap_ratio"), [xm]), "ipc_class_at_max": (("start", "gap_ratio"), [[2] * 3])},
                          coords={"gap_ratio": g, "start": ["centre"]})

    base = [0.6, 0.4, 0.5]
    specs = [dict(damper="cid", mu=0.01, e=0.25, nu=nu) for nu in (0.0, 0.05, 0.5)]
    fig, ax = plt.subplots()
    drawn = []
    for spec, xm in zip(specs, (base, [x + 1e-3 for x in base], [0.9, 0.8, 0.7])):
        plotting._draw_curve(ax, sweep(xm), spec, "C0", drawn)
    labels = [h.get_label() for h in ax.get_legend_handles_labels()[0]]
    plt.close(fig)
    assert labels == ["CID μ=0.01 e=0.25, start centre; CID μ=0.01 e=0.25 ν=0.05, start centre (on it)",
                      "CID μ=0.01 e=0.25 ν=0.5, start centre"]
