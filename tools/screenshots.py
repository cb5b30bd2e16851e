"""Screenshots of both reports of a finished study, with headless Chromium, to look at as a reader does.

    python tools/screenshots.py [--results results] [--out results/screenshots] [--configfile ...]

The HTML report (results/report/index.html) is taken at its top and at each of its sections (Chromium scrolls to a
URL's fragment); Snakemake's own report (built here with `snakemake --report`, into results/report-snakemake.html)
at its landing page.  Each shot is a PNG of a 1280-pixel-wide window, the width of a laptop's screen.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

WIDTH, HEIGHT = 1280, 1600


def chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    raise SystemExit("screenshots: no chromium on PATH (apt-get install chromium)")


def shoot(url: str, out: Path, height: int = HEIGHT) -> None:
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                        f"--user-data-dir={profile}", f"--window-size={WIDTH},{height}", "--virtual-time-budget=8000",
                        f"--screenshot={out}", url], check=True, capture_output=True, timeout=120)
    print(out)


def alone_page(html: str, section: str) -> str:
    """The report's page showing one section alone.  An attribute selector, not #id: ids hold dots
    (ida_s3_T0.5), which an #id selector reads as a class, and the section would stay hidden."""
    style = f"<style>header,nav,h2,section{{display:none}}section[id='{section}']{{display:block}}</style>"
    return html.replace("</head>", style + "</head>", 1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--results", default="results", help="the study's results folder")
    ap.add_argument("--out", default=None, help="where the PNGs go (default: <results>/screenshots)")
    ap.add_argument("--configfile", nargs="*", default=[], help="the configuration files the study ran with")
    args = ap.parse_args(argv)
    results = Path(args.results).resolve()
    out = Path(args.out) if args.out else results / "screenshots"
    out.mkdir(parents=True, exist_ok=True)
    page = results / "report" / "index.html"
    if not page.is_file():
        raise SystemExit(f"screenshots: {page} is missing: build it first (snakemake results/report/index.html)")
    shoot(page.as_uri(), out / "report-top.png")
    html = page.read_text(encoding="ascii")
    with tempfile.TemporaryDirectory() as tmp:
        for section in re.findall(r'<section id="([^"]+)"', html):
            # the page with that section alone (Chromium's screenshot is of the window, and scrolling to a
            # fragment before it paints is not reliable)
            alone = Path(tmp) / f"{section}.html"
            alone.write_text(alone_page(html, section), encoding="ascii")
            shoot(alone.as_uri(), out / f"report-{section}.png")
    smk = results / "report-snakemake.html"
    config = ["--configfile", *args.configfile] if args.configfile else []
    subprocess.run([sys.executable, "-m", "snakemake", "--report", str(smk), *config], cwd=results.parent,
                   check=True, capture_output=True)
    shoot(smk.as_uri(), out / "snakemake-report.png", height=1000)
    return 0


if __name__ == "__main__":
    sys.exit(main())
