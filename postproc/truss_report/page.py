"""truss_report.page: see the package docstring (postproc/truss_report/__init__.py)."""
import datetime
import gc
import html
import os
import sys

import numpy as np



def esc(s):
    return html.escape(str(s), quote=True)


# Shown for a value that does not apply or is not defined (the DASH_NOTE footnote says so).
DASH = "—"
DASH_NOTE = ("— : the value does not apply here or is not defined by the data (for example the "
             "interval after the last bay to lock, a bound the sample is too small for, the "
             "acceptance of a level without Markov steps, a resistance the file does not hold); "
             "the text beside each table says which.")

# Units as the report spells them: a space between the factors (SI style, as "mN m").
UNIT_SPELLING = {"Nm": "N m", "Ns": "N s", "Nm/rad": "N m/rad", "N/m": "N/m"}


def unit_text(u):
    """A unit as the page spells it ("Nm" in a dataset's units attribute is shown "N m")."""
    return UNIT_SPELLING.get(u, u)


def unit_html(u):
    """A unit after a number in a table: its spelling, never broken across lines ("mN m")."""
    return esc(unit_text(u)).replace(" ", "\u00a0")


def fmt(v, digits=5):
    """Rounded text of a number (integers exact); DASH for NaN."""
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    v = float(v)
    if np.isnan(v):
        return DASH
    text = f"{v:.{digits}g}".replace("inf", "∞")
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text   # never "-0"


def digits_for(values, least=3, most=8):
    """Significant digits that show how the `values` (the numbers of one row or one quantity)
    differ: two significant digits of their spread (max - min) and one of their smallest nonzero
    gap, at the size of the largest |value|; at least `least`, at most `most`."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    big = float(np.max(np.abs(v))) if len(v) else 0.0
    if not big > 0:
        return least
    mag = np.floor(np.log10(big))
    d = least
    if np.ptp(v) > 0:
        d = max(d, int(mag - np.floor(np.log10(np.ptp(v)))) + 2)
    gaps = np.diff(np.unique(v))
    gaps = gaps[gaps > 0]
    if len(gaps):
        d = max(d, int(mag - np.floor(np.log10(np.min(gaps)))) + 1)
    return int(min(most, d))


def data_value(v):
    return str(int(v)) if isinstance(v, (int, np.integer)) else repr(float(v))


def num(key, v, unit="", digits=5, tag="td", factor=1.0):
    """A table cell (or span) holding one number, with its data-key and full-precision value;
    shown as v / factor in `unit` (a display unit: factor 1e-3 for "mN"), kept in SI."""
    shown = v / factor if factor != 1.0 and not isinstance(v, (int, np.integer)) else v
    text = fmt(shown, digits)
    if unit and unit != "1" and text != DASH:
        text += "\u00a0" + unit_html(unit)
    cls = ' class="num"' if tag == "td" else ""
    return f'<{tag}{cls} data-key="{esc(key)}" data-value="{data_value(v)}">{text}</{tag}>'


def table(headers, rows, cls="", attrs=None):
    """headers: header HTML (no header row when all are empty); rows: lists of cells, each a
    <td>/<th> string or text to wrap in <td>."""
    body = []
    for i, row in enumerate(rows):
        cells = "".join(c if c.startswith(("<td", "<th")) else f"<td>{c}</td>" for c in row)
        extra = f" {attrs[i]}" if attrs else ""
        body.append(f"<tr{extra}>{cells}</tr>")
    head = ("<thead><tr>" + "".join(f"<th>{h}</th>" for h in headers) + "</tr></thead>"
            if any(headers) else "")
    return f'<table class="{cls}">{head}<tbody>{"".join(body)}</tbody></table>'


def unit_label(u):
    return "" if u == "1" else f" ({unit_text(u)})"


class Page:
    """The report being built: HTML parts, figures saved into the staging directory, and the
    results of the consistency checks against the file's own /stats."""

    def __init__(self, outdir, plt, progress=None):
        self.dir, self.plt = outdir, plt
        self.files = []
        self.checks = []          # (what, passed, detail html)
        self.progress = progress or (lambda what: None)
        self.children = []        # (pid, figure name) of the figures being drawn
        self.max_children = 2
        # Fonts and text layout are cached per process: draw once here, so that every forked
        # child starts with them loaded instead of loading them again.
        warm, ax = plt.subplots(figsize=(2, 1))
        ax.set_title("µ−0.5 (mN m)")
        ax.set_xlabel("x")
        warm.savefig(os.devnull, format="png", dpi=150)
        plt.close(warm)

    def figure(self, fig, name, caption, cls="wide"):
        """Saves `fig` as DIR/name and returns its HTML. The layout, drawing and PNG encoding
        (two thirds of a figure's cost; the figures lay themselves out at draw time) happen in a
        forked child while this process goes on with the next section: the report's figures
        then use both cores. finish() waits for them."""
        if len(self.files) % 5 == 0:
            self.progress(f"figure {len(self.files) + 1}: {name}")
        while len(self.children) >= self.max_children:
            self._reap(self.children.pop(0))
        sys.stdout.flush()
        sys.stderr.flush()
        gc.freeze()        # the child's collector leaves the parent's objects (and pages) alone
        pid = os.fork()
        if pid == 0:       # child: draw, encode, leave without Python's exit handlers
            code = 0
            try:
                fig.savefig(os.path.join(self.dir, name), format="png", dpi=150,   # sharp on paper
                            pil_kwargs={"compress_level": 3})
            except BaseException as e:   # noqa: BLE001 - reported through the exit status
                sys.stderr.write(f"error: figure {name}: {e}\n")
                code = 1
            os._exit(code)
        self.children.append((pid, name))
        self.plt.close(fig)
        self.files.append(name)
        return (f'<figure class="{cls}"><img src="{esc(name)}" alt="{esc(caption)}">'
                f"<figcaption>{esc(caption)}</figcaption></figure>")

    def _reap(self, child):
        pid, name = child
        _, status = os.waitpid(pid, 0)
        if os.waitstatus_to_exitcode(status) != 0:
            raise RuntimeError(f"drawing the figure {name} failed")

    def finish(self):
        """Waits for every figure (RuntimeError if one failed)."""
        while self.children:
            self._reap(self.children.pop(0))

    def check(self, what, passed, detail):
        self.checks.append((what, passed, detail))


CSS = """
body { font-family: "DejaVu Sans", Arial, sans-serif; font-size: 14px; margin: 24px auto;
       max-width: 1400px; color: #222; padding: 0 16px; }
h1 { font-size: 24px; margin-bottom: 4px; } h2 { border-bottom: 2px solid #345; margin-top: 36px; }
h3 { margin-top: 24px; } .meta { color: #555; font-size: 12px; }
nav { background: #eef2f6; padding: 6px 10px; margin: 12px 0; }
table { border-collapse: collapse; margin: 8px 0 14px 0; font-size: 13px; }
th, td { border: 1px solid #c8cdd3; padding: 3px 8px; text-align: left; vertical-align: top; }
thead th { background: #e6ebf0; } table.kv th { background: #f3f5f7; width: 380px; }
td.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
td.toosmall { color: #8a5a00; } table.corr td.num { min-width: 70px; }
figure { margin: 8px 0 16px 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figure.half img { max-width: 100%; } figcaption { font-size: 12px; color: #555; }
.flex { display: flex; flex-wrap: wrap; gap: 0 18px; align-items: flex-start; }
.grid { display: grid; grid-template-columns: 1fr 1fr; gap: 12px 24px; }
.note { color: #555; font-style: italic; }
.warn { background: #fde8e8; border: 1px solid #d33; padding: 8px; }
.okc { color: #176b17; font-weight: bold; } .bad { color: #c00; font-weight: bold; }
pre { background: #f6f8fa; padding: 8px; font-size: 12px; overflow-x: auto; }
details { margin: 6px 0 12px 0; } summary { cursor: pointer; color: #234; }
.verdict { padding: 8px 12px; margin: 8px 0; border-radius: 4px; font-size: 14px; }
.verdict ul { margin: 4px 0 4px 18px; padding: 0; } .small { font-size: 11px; color: #444; }
.verdict.fail { background: #fde8e8; border: 2px solid #c00; }
.verdict.pass { background: #e7f6e7; border: 2px solid #176b17; }
.verdict.not_assessed { background: #fff4d6; border: 2px solid #b37400; }
table.document th { background: #f3f5f7; width: 200px; } table.document td { word-break: break-all; }
.dash { font-size: 11px; color: #444; }
table.design td, table.design th { font-size: 12px; } table.design td small { color: #555; }
h2#design, h2#mechanism { margin-top: 14px; }
table.signoff td { min-width: 180px; height: 36px; }
@media print { table.signoff { width: 100%; } table.signoff td { height: 14mm; } }
@media print {
  body { font-size: 10pt; max-width: none; margin: 0; padding: 0; }
  nav, details > summary { display: none; } details { display: block; }
  h2 { page-break-after: avoid; } figure, table, .verdict { page-break-inside: avoid; }
  figure img { max-width: 100%; border: none; } a { color: inherit; text-decoration: none; }
  .grid { display: block; } table { font-size: 8pt; } table.design td, table.design th { font-size: 7pt; }
  td.num { white-space: normal; } pre { white-space: pre-wrap; font-size: 7pt; }
}
@page { size: A4; margin: 15mm 12mm 18mm 12mm;
        @bottom-left { content: string(doctitle); font-size: 8pt; color: #555; }
        @bottom-right { content: "page " counter(page) " of " counter(pages); font-size: 8pt;
                        color: #555; } }
h1 { string-set: doctitle content(); }
"""


def document_block(rows):
    """The document block: what was judged, by which tool, from which file (name and SHA-256),
    when, and the verdict; the same on the HTML page and in the PDF."""
    return ("<table class='kv document' data-key='document'>"
            + "".join(f"<tr><th>{esc(k)}</th><td data-doc='{esc(k)}'>{v}</td></tr>"
                      for k, v in rows) + "</table>")


def html_page(title, path, sha256, body, doc=()):
    """The page: title, document block (`doc`: extra (name, html) rows, e.g. campaign, tool,
    verdict), the "—" footnote, then `body`."""
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    rows = list(doc) + [("report built (UTC)", esc(now)),
                        ("results file", f"<code>{esc(os.path.basename(path))}</code>"),
                        ("results file SHA-256", f"<code data-key='sha256'>{esc(sha256)}</code>"),
                        ("results file path", f"<code>{esc(os.path.abspath(path))}</code>")]
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f"<title>{esc(title)}</title><style>{CSS}</style></head><body>\n"
            f"<h1>{esc(title)}</h1>\n{document_block(rows)}\n"
            f"<p class='dash' id='dash'>{esc(DASH_NOTE)}</p>\n"
            f"{body}\n</body></html>\n")
