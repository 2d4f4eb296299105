"""truss_report.page.html: the HTML of the report: numbers with their data-key and full-precision
data-value, shown by the report's number rule (page.numbers), tables, the document block and the
page."""
import datetime
import html
import os

import numpy as np

from .numbers import DASH, fmt, fmt_at, unit_html, unit_text
from .style import CSS


def esc(s):
    return html.escape(str(s), quote=True)


DASH_NOTE = ("— : the value does not apply here or is not defined by the data (for example the "
             "interval after the last bay to lock, a bound the sample is too small for, the "
             "acceptance of a level without Markov steps, a resistance the file does not hold); "
             "the text beside each table says which.")


def data_value(v):
    return str(int(v)) if isinstance(v, (int, np.integer)) else repr(float(v))


def num(key, v, unit="", digits=5, tag="td", factor=1.0, at=None, text=None):
    """A table cell (or span) holding one number, with its data-key and full-precision value;
    shown as v / factor in `unit` (a display unit: factor 1e-3 for "mN"), kept in SI: to the
    resolution 10^at of its quantity (page.numbers, rule 1) when `at` is given, else with `digits`
    significant digits; `text` replaces the shown number (a probability's "< 3.0e-04")."""
    shown = v / factor if factor != 1.0 and not isinstance(v, (int, np.integer)) else v
    if text is None:
        text = fmt_at(shown, at) if at is not None else fmt(shown, digits)
    else:
        text = esc(text)
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
