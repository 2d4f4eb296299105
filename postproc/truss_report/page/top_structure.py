"""truss_report.page.top_structure: the structural margins table (judging.structure): per load and
limit the declared allowable, the factor of safety, the design load and the margin of safety
MoS = allowable / (FoS x design load) - 1, and per bay where the file records the load per bay."""
import numpy as np

from ..judging.structure import CONFIRM, LOADS, NOT_ASSESSED, STANDARD, load_status
from ..judging.verdict import VERDICT_WORDS
from .html import esc, num, table
from .numbers import DASH, fmt, fmt_at, resolution, unit_html
from .top_mechanism import percent_cell

LIMIT_WORDS = {"yield": "yield (FOSY)", "ultimate": "ultimate (FOSU)"}
LOAD_KEYS = {stem: key for stem, key, _share, _part, _unit in LOADS}


def quantity_cell(key, v, load_key, unit, du):
    """A load or allowable in its design load's display unit (one prefix per quantity)."""
    lab, f = du.get(load_key, unit, [v])
    text = fmt_at(v / f, du.at(load_key)) if np.isfinite(v) else DASH
    if text != DASH:
        text += "\u00a0" + unit_html(lab)
    return f'<td class="num" data-key="{esc(key)}" data-value="{repr(float(v))}">{text}</td>'


def margin_row(m, key, du, at):
    """Cells of one margin: allowable, factor, design load, MoS, status."""
    status = m.status if np.isfinite(m.allowable) else NOT_ASSESSED
    load_key = LOAD_KEYS[m.stem]
    return [quantity_cell(f"{key}.allowable", m.allowable, load_key, m.unit, du),
            num(f"{key}.factor", m.factor),
            quantity_cell(f"{key}.design_load", m.design_load, load_key, m.unit, du),
            percent_cell(f"{key}.mos", m.margin, at),
            f"<td data-key='{esc(key)}.status'>{VERDICT_WORDS[status]}"
            + (f": {esc(m.reason)}" if m.reason else "") + "</td>"]


def bay_table(bays, at):
    """One row per bay: the smallest MoS of each load the file records per bay (over its limits)."""
    stems = list(dict.fromkeys(m.stem for m in bays))
    by = {(m.bay, m.stem): m for m in sorted(bays, key=lambda m: -m.margin if np.isfinite(m.margin) else 0.0)}
    rows = []
    for bay in sorted({m.bay for m in bays if m.bay is not None}):
        cells = [f"bay {bay}"]
        for stem in stems:
            m = by.get((bay, stem))
            cells.append(percent_cell(f"structure.bay{bay}.{stem}.mos", m.margin, at) if m is not None
                         else f"<td class='num'>{DASH}</td>")
        rows.append(cells)
    return table(["bay"] + [f"{esc(s.replace('_', ' '))}: smallest MoS" for s in stems], rows)


def structure_html(margins, bays, level, confidence, du):
    """The section; every load the campaign has is listed, declared or not."""
    head = "<h2 id='structure'>Structural margins</h2>"
    if not margins:
        return head + "<p>No load of the structure in the file: not assessed.</p>"
    text = (f"<p>Margin of safety MoS = allowable / (FoS × design load) − 1 ({esc(STANDARD)}), the design "
            f"load being the upper {fmt(100 * confidence)} % confidence bound of P{fmt(level)} (the design-load "
            f"table). Allowables and factors are the scene's [structure] table. {esc(CONFIRM)} A load with "
            "no declared allowable is NOT ASSESSED.</p>")
    at = resolution([100 * m.margin for m in list(margins) + list(bays) if np.isfinite(m.margin)])
    rows = [[f"{esc(m.stem.replace('_', ' '))} ({esc(m.part)}): {LIMIT_WORDS[m.limit]}",
             *margin_row(m, f"structure.{m.stem}.{m.limit}", du, at)] for m in margins]
    loads = list(dict.fromkeys(m.stem for m in margins))
    summary = "<p>" + "; ".join(f"{esc(s.replace('_', ' '))}: <b data-key='structure.{s}'>"
                                f"{VERDICT_WORDS[load_status(margins, s)]}</b>" for s in loads) + ".</p>"
    out = head + text + table(["load: limit", "allowable", "FoS", "design load", "MoS", "status"], rows) + summary
    if bays:
        out += ("<h3>Per bay</h3><p class='small'>The smallest margin of each load over its declared limits, "
                "from each bay's own design load (the upper bound of the same percentile of that bay's values), "
                "for the loads the file records per bay.</p>" + bay_table(bays, at))
    return out
