#!/usr/bin/python3
"""The signed PDF holds what the HTML holds, and nothing is printed outside the page's margins.

Usage:
    test_pdf_layout.py --scratch DIR [--repo REPO --shipped DIR] [--h5 RESULTS.h5 ...] [--report DIR ...]

Reports to check: every shipped campaign's (campaigns/*.toml run small on 2 ranks, reported by
shipped_reports.py into --shipped DIR), those of the given results files (--h5: built here) and
reports already built (--report DIR with report.html and report.pdf). For each:
1. Every value the HTML carries, the text of each element with a data-key and of each table cell,
   appears in the PDF's text (pdftotext -raw; both compared without whitespace and in Unicode
   NFKC form, so that a cell wrapped over lines still matches): a table clipped at the page's
   edge loses its last column's digits and units ("125 rad/s" printed as "12").
2. No page holds only a heading: each page has more than one line of text besides its footer.
3. The number rule (number_format.py) on the HTML's visible text and on the PDF's text: units "N m"
   not "Nm", no "-0", "nan" or "inf", at most five significant digits, torques in one prefix.
4. Every figure the HTML shows is in the PDF as that very PNG: an image of the PDF (pdfimages)
   with the PNG file's size and pixels exactly (both lossless): drawn once, shared by both.
5. No ink outside the page's margins (A4, margins 15 mm top, 12 mm left and right; the footer's
   bottom margin is left out): each page rendered at 50 dpi in grey (pdftoppm), a strip 1 mm
   inside each margin's edge must be white (every pixel >= 250 of 255). A box wider than the
   text width prints into the right margin or off the page.
Prints one line per check; exit 0 when all pass, 1 otherwise.
"""
import argparse
import glob
import html
import html.parser
import os
import re
import subprocess
import sys
import tempfile
import unicodedata

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from number_format import violations  # noqa: E402

PY = "/usr/bin/python3"
from checks import FAILS, check  # noqa: E402  (this script's folder is on sys.path)
from shipped_reports import report_dirs  # noqa: E402
MM = 50 / 25.4            # pixels per mm at 50 dpi
MARGINS_MM = {"top": 15.0, "left": 12.0, "right": 12.0}


def squash(text):
    return "".join(unicodedata.normalize("NFKC", text).split())


class Values(html.parser.HTMLParser):
    """The text of every element with a data-key and of every td / th, as printed: without the
    parts the print stylesheet hides (nav, details' summary) and without the <style>."""

    def __init__(self):
        super().__init__()
        self.open, self.values, self.hidden = [], [], 0

    def handle_starttag(self, tag, attrs):
        if tag in ("br", "img", "meta", "col"):
            return
        a = dict(attrs)
        hide = tag in ("nav", "summary", "style", "title")
        self.hidden += hide
        self.open.append([tag, a.get("data-key"), [], hide])

    def handle_endtag(self, tag):
        while self.open:
            t, key, parts, hide = self.open.pop()
            self.hidden -= hide
            text = "".join(parts)
            if (key is not None or t in ("td", "th")) and squash(text):
                self.values.append((key or t, text.strip()))
            if self.open:
                self.open[-1][2].append(text)
            if t == tag:
                break

    def handle_data(self, data):
        if self.open and not self.hidden:
            self.open[-1][2].append(data)


def html_values(path):
    p = Values()
    with open(path, encoding="utf-8") as fh:
        p.feed(fh.read())
    return p.values


def pdf_text(pdf):
    return subprocess.run(["pdftotext", "-raw", pdf, "-"], capture_output=True, text=True, check=True).stdout


def check_pages(name, raw):
    """Pages whose only text besides the footer is one line (a heading left alone)."""
    lonely = []
    for i, page in enumerate(raw.split("\f")[:-1], 1):
        lines = [ln for ln in page.splitlines() if ln.strip() and not ln.strip().startswith(
            ("Load report", "Design-sweep report", "Failure-probability report", "Single-run report"))
            and "page " not in ln]
        if len(lines) <= 1:
            lonely.append(f"page {i}: {lines}")
    check(not lonely, f"{name}: no page holding only a heading" + (f" ({lonely[:3]})" if lonely else ""))


def check_values(name, out):
    values = html_values(os.path.join(out, "report.html"))
    raw = pdf_text(os.path.join(out, "report.pdf"))
    check_pages(name, raw)
    text = squash(raw)
    missing = [(k, v) for k, v in values if squash(v) not in text]
    check(not missing and len(values) > 20,
          f"{name}: all {len(values)} values of the HTML in the PDF's text"
          + (f"; {len(missing)} missing, e.g. {missing[:4]}" if missing else ""))


def visible_text(path):
    """(the HTML's text as a reader sees it: without the style sheet, the tags and the attributes;
    the text of its <pre> blocks). A <pre> block is a file shown verbatim (the campaign's TOML, the
    signed record of its inputs), whose numbers are as the user typed them: the rule is not for it."""
    with open(path, encoding="utf-8") as fh:
        page = re.sub(r"<(style|script)\b.*?</\1>", " ", fh.read(), flags=re.S)
    pre = html.unescape(" ".join(re.findall(r"<pre\b[^>]*>(.*?)</pre>", page, flags=re.S)))
    page = re.sub(r"<pre\b.*?</pre>", " ", page, flags=re.S)
    return html.unescape(re.sub(r"<[^>]+>", " ", page)), pre


def check_numbers(name, out):
    text, pre = visible_text(os.path.join(out, "report.html"))
    verbatim = squash(pre)
    printed = "\n".join(ln for ln in pdf_text(os.path.join(out, "report.pdf")).splitlines()
                         if not (squash(ln) and squash(ln) in verbatim))
    for what, text in (("HTML", text), ("PDF", printed)):
        bad = violations(text)
        check(not bad, f"{name}: the {what} keeps the number rule" + (f" ({len(bad)} places, e.g. {bad[:4]})"
                                                                      if bad else ""))


def check_figures(name, out):
    from PIL import Image
    with open(os.path.join(out, "report.html"), encoding="utf-8") as fh:
        shown = sorted(set(re.findall(r"<img [^>]*src=\"([^\"]+)\"", fh.read())))
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(["pdfimages", "-png", os.path.join(out, "report.pdf"), os.path.join(tmp, "i")], check=True)
        embedded = [np.asarray(Image.open(p).convert("RGB")) for p in sorted(glob.glob(os.path.join(tmp, "i-*.png")))]
    missing = []
    for src in shown:
        want = np.asarray(Image.open(os.path.join(out, src)).convert("RGB"))
        if not any(g.shape == want.shape and np.array_equal(g, want) for g in embedded):
            missing.append(src)
    check(not missing, f"{name}: all {len(shown)} figures of the HTML in the PDF, pixel for pixel"
          + (f"; {len(missing)} not, e.g. {missing[:3]}" if missing else ""))


def ink_outside(png):
    """The margins (top, left, right) whose strip 1 mm inside the page's edge holds ink."""
    import matplotlib.image as mi
    a = mi.imread(png)
    a = (a if a.ndim == 2 else a[..., :3].mean(axis=2)) * (255 if a.max() <= 1.0 else 1)
    h, w = a.shape
    strips = {"top": a[:int((MARGINS_MM["top"] - 1) * MM), :],
              "left": a[:, :int((MARGINS_MM["left"] - 1) * MM)],
              "right": a[:, w - int((MARGINS_MM["right"] - 1) * MM):]}
    return [side for side, s in strips.items() if s.size and np.min(s) < 250]


def check_margins(name, out):
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(["pdftoppm", "-r", "50", "-gray", "-png", os.path.join(out, "report.pdf"),
                        os.path.join(tmp, "p")], check=True)
        bad = []
        for png in sorted(glob.glob(os.path.join(tmp, "p-*.png"))):
            sides = ink_outside(png)
            if sides:
                bad.append(f"page {int(png.rsplit('-', 1)[1][:-4])}: {', '.join(sides)}")
    check(not bad, f"{name}: no ink in the margins" + (f" ({'; '.join(bad[:6])})" if bad else ""))


def report(h5, out):
    p = subprocess.run([PY, os.path.join(os.path.dirname(__file__), "..", "..", "postproc", "report.py"), h5,
                        "-o", out, "--force", "--quiet"], capture_output=True, text=True)
    return check(p.returncode in (0, 3, 4) and os.path.exists(os.path.join(out, "report.pdf")),
                 f"{os.path.basename(h5)}: report and PDF written (exit {p.returncode}) {p.stderr.strip()[-300:]}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scratch", required=True)
    ap.add_argument("--repo")
    ap.add_argument("--shipped", help="the reports of the shipped campaigns (shipped_reports.py); needs --repo")
    ap.add_argument("--h5", nargs="*", default=[])
    ap.add_argument("--report", nargs="*", default=[])
    a = ap.parse_args()
    os.makedirs(a.scratch, exist_ok=True)
    todo = [(os.path.basename(d.rstrip("/")), d) for d in a.report]
    todo += report_dirs(a.repo, a.shipped) if a.shipped else []
    files = [(os.path.basename(h)[:-3], h) for h in a.h5]
    for name, h5 in files:
        out = os.path.join(a.scratch, f"report_{name}")
        if report(h5, out):
            todo.append((name, out))
    for name, out in todo:
        check_values(name, out)
        check_numbers(name, out)
        check_figures(name, out)
        check_margins(name, out)
    print(f"{len(FAILS)} failed" if FAILS else "all passed")
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
