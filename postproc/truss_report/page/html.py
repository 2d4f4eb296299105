"""truss_report.page.html: the HTML of the report: numbers with their data-key and full-precision
data-value, rounded for the eye (fmt, digits_for), units as the page spells them, tables, the
document block and the page."""
import datetime
import html
import os

import numpy as np

from .style import CSS


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
