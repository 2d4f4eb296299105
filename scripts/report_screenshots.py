#!/usr/bin/python3
"""The report's screenshots in docs/images, cut from the PDF as it prints: the ECSS motorisation
table and the input tables (dispersions and base scene) of the default campaign's report, and
page 1 of the motor-sizing sweep's report.

Usage:
    scripts/report_screenshots.py DEFAULT.h5 SWEEP.h5 [--out docs/images] [--scratch /tmp/truss] [--dpi 100]

DEFAULT.h5: campaigns/table1_dispersed.toml's results (scripts/run_main.sh writes it);
SWEEP.h5: campaigns/motor_sizing.toml's (mpirun -np 2 build/truss-campaign campaigns/motor_sizing.toml
-o SWEEP.h5). Builds both reports with postproc/report.py, each file linked as
SCRATCH/out/<campaign>/<campaign>.h5 (the path scripts/run_main.sh gives it, which the reports
show), renders the pages with pdftoppm and cuts each picture between two of the PDF's named
destinations (the HTML's element ids, pdfinfo -dests): from its heading down to the next part (a
picture over a page break is the parts one under the other), the text's width and 2 mm either
side; page 1 of the sweep whole, within its margins. Reduced to 64 colours. Exit 1 when a report
or a destination is missing.
"""
import argparse
import os
import re
import subprocess
import sys

from PIL import Image

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PT_PER_MM = 72 / 25.4
PAGE_PT = (595.28, 841.89)                       # A4
MARGIN_MM = {"top": 15.0, "bottom": 18.0, "left": 12.0, "right": 12.0}   # page.style's @page
PAD_MM = 2.0
# picture: (report, first destination, destination it ends above)
CUTS = {"report_motorisation_table.png": ("default", "mechanism", "structure"),
        "report_input_tables.png": ("default", "dispersions", "base-scene-toml")}


def build_report(h5, name, scratch):
    """The report of `h5` linked as scratch/out/name/name.h5; the path of its PDF."""
    link = os.path.join(scratch, "out", name, f"{name}.h5")
    os.makedirs(os.path.dirname(link), exist_ok=True)
    if os.path.lexists(link):
        os.remove(link)
    os.symlink(os.path.abspath(h5), link)
    out = os.path.join(scratch, "out", name, "report")
    p = subprocess.run(["/usr/bin/python3", os.path.join(REPO, "postproc", "report.py"), link, "-o", out,
                        "--force", "--quiet"], capture_output=True, text=True)
    if p.returncode not in (0, 3, 4):
        sys.exit(f"error: the report of {h5} failed (exit {p.returncode}): {p.stderr.strip()[-400:]}")
    return os.path.join(out, "report.pdf")


def destinations(pdf):
    """{name: (page, y from the page's top in points)} of the PDF's named destinations."""
    text = subprocess.run(["pdfinfo", "-dests", pdf], capture_output=True, text=True, check=True).stdout
    res = {}
    for m in re.finditer(r"^\s*(\d+)\s+\[\s*XYZ\s+[-\d.]+\s+([-\d.]+)[^\]]*\]\s+\"([^\"]+)\"", text, re.M):
        res[m.group(3)] = (int(m.group(1)), PAGE_PT[1] - float(m.group(2)))
    return res


def page_image(pdf, page, dpi, scratch):
    stem = os.path.join(scratch, f"{os.path.basename(os.path.dirname(os.path.dirname(pdf)))}_page{page}")
    subprocess.run(["pdftoppm", "-png", "-r", str(dpi), "-f", str(page), "-l", str(page), "-singlefile",
                    pdf, stem], check=True)
    return Image.open(stem + ".png").convert("RGB")


def cut(pdf, start, end, dpi, scratch):
    """The text area from (page, y) `start` down to `end`, over page breaks, one picture."""
    px = dpi / 72.0
    left = (MARGIN_MM["left"] - PAD_MM) * PT_PER_MM * px
    right = (PAGE_PT[0] - (MARGIN_MM["right"] - PAD_MM) * PT_PER_MM) * px
    top_of_text = (MARGIN_MM["top"] - PAD_MM) * PT_PER_MM
    bottom_of_text = PAGE_PT[1] - (MARGIN_MM["bottom"] - PAD_MM) * PT_PER_MM
    parts = []
    for page in range(start[0], end[0] + 1):
        y0 = start[1] - PAD_MM * PT_PER_MM if page == start[0] else top_of_text
        y1 = end[1] - PAD_MM * PT_PER_MM if page == end[0] else bottom_of_text
        if y1 > y0:
            img = page_image(pdf, page, dpi, scratch)
            parts.append(img.crop((round(left), round(y0 * px), round(right), round(y1 * px))))
    if not parts:
        sys.exit(f"error: {pdf}: nothing between {start} and {end}")
    res = Image.new("RGB", (parts[0].width, sum(p.height for p in parts)), "white")
    y = 0
    for p in parts:
        res.paste(p, (0, y))
        y += p.height
    return res


def text_area(pdf, page, dpi, scratch):
    """A whole page within its margins (and 2 mm), the footer included."""
    px = dpi / 72.0
    img = page_image(pdf, page, dpi, scratch)
    box = ((MARGIN_MM["left"] - PAD_MM) * PT_PER_MM, (MARGIN_MM["top"] - PAD_MM) * PT_PER_MM,
           PAGE_PT[0] - (MARGIN_MM["right"] - PAD_MM) * PT_PER_MM, PAGE_PT[1] - 8 * PT_PER_MM)
    return img.crop(tuple(round(v * px) for v in box))


def save(img, path):
    img.quantize(colors=64, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    print(path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("default_h5")
    ap.add_argument("sweep_h5")
    ap.add_argument("--out", default=os.path.join(REPO, "docs", "images"))
    ap.add_argument("--scratch", default="/tmp/truss")
    ap.add_argument("--dpi", type=int, default=100)
    a = ap.parse_args()
    scratch = os.path.abspath(a.scratch)
    os.makedirs(a.out, exist_ok=True)
    pdfs = {"default": build_report(a.default_h5, "table1_dispersed", scratch),
            "sweep": build_report(a.sweep_h5, "motor_sizing", scratch)}
    dests = {k: destinations(v) for k, v in pdfs.items()}
    for name, (which, first, end) in CUTS.items():
        missing = [d for d in (first, end) if d not in dests[which]]
        if missing:
            sys.exit(f"error: {pdfs[which]}: no destination {', '.join(missing)} (an element id of the HTML)")
        save(cut(pdfs[which], dests[which][first], dests[which][end], a.dpi, scratch), os.path.join(a.out, name))
    save(text_area(pdfs["sweep"], 1, a.dpi, scratch), os.path.join(a.out, "report_sweep_page1.png"))


if __name__ == "__main__":
    main()
