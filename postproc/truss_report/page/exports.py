"""truss_report.page.exports: the report's tables as small files beside report.pdf, for a design
database or CI (docs/report.md "Exports"): design_loads.csv, structural_margins.csv,
motorisation.csv, bay_loads.csv (a load report), sweep.csv (a design sweep) and verdict.json
(both). Each CSV is written from the objects the page renders its table from (the judged design
loads, margins and sweep table), in SI units at full precision (17 significant digits: they read
back to the float64 values; NaN as "nan", as runs.csv), with the unit of each column in the header
row: "name [unit]", "[unit]" naming the row's `unit` column where the rows differ in unit."""
import csv
import html
import io
import json
import re

import numpy as np

from ..judging.verdict import VERDICT_WORDS
from .numbers import unit_text

DESIGN_CSV, STRUCTURE_CSV, MOTOR_CSV = "design_loads.csv", "structural_margins.csv", "motorisation.csv"
BAYS_CSV, SWEEP_CSV, VERDICT_JSON = "bay_loads.csv", "sweep.csv", "verdict.json"
TAGS = re.compile(r"<[^>]+>")
DATA = re.compile(r"data-key=[\"']([^\"']+)[\"'][^>]*data-value=[\"']([^\"']*)[\"']")
TORQUE_KEYS = {"mech.s_design", "mech.d_design", "mech.losses", "mech.t_min", "mech.t_avail_min",
               "mech.stall_needed", "mech.stall_scene"}
SPEED_KEYS = {"mech.omega", "mech.omega0"}


def plain(text):
    """HTML as plain text (tags dropped, entities resolved, spaces joined)."""
    return " ".join(html.unescape(TAGS.sub("", str(text))).split())


def cell(v):
    if isinstance(v, (bool, np.bool_)):
        return str(bool(v)).lower()
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, (float, np.floating)):
        return "%.17g" % float(v)
    return "" if v is None else str(v)


def csv_text(columns, rows):
    """CSV with a header row of "name [unit]" ("name" alone for text and flags)."""
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow([f"{name} [{unit}]" if unit else name for name, unit in columns])
    for row in rows:
        w.writerow([cell(v) for v in row])
    return out.getvalue()


def design_csv(loads, confidence):
    """One row per design load (design-load table; values in the row's unit)."""
    levels = [lv.level for lv in loads[0].levels] if loads else []
    cols = [("load", ""), ("label", ""), ("unit", ""), ("n", "1"), ("nominal", "unit"), ("mean", "unit")]
    for q in levels:
        cols += [(f"P{q:g}", "unit"), (f"upper {100 * confidence:g} % bound of P{q:g}", "unit"),
                 (f"rank k of the bound of P{q:g}", "1"), (f"runs the bound of P{q:g} needs", "1")]
    cols += [(f"P{levels[-1]:g} / nominal" if levels else "ratio", "1")]
    rows = []
    for d in loads:
        row = [d.key, d.label, unit_text(d.unit), d.n, d.nominal, d.mean]
        for lv in d.levels:
            row += [lv.estimate, lv.bound, lv.rank if lv.rank else "", lv.n_needed or ""]
        rows.append(row + [d.ratio])
    return csv_text(cols, rows)


def structure_csv(margins, bays):
    """One row per load and limit, then per bay (bay empty: the whole run)."""
    cols = [("load", ""), ("part", ""), ("limit", ""), ("bay", "1"), ("unit", ""), ("allowable", "unit"),
            ("FoS", "1"), ("design load", "unit"), ("MoS", "1"), ("status", ""), ("reason", "")]
    rows = [[m.stem, m.part, m.limit, m.bay if m.bay is not None else "", m.unit, m.allowable, m.factor,
             m.design_load, m.margin, VERDICT_WORDS[m.status], m.reason] for m in list(margins) + list(bays)]
    return csv_text(cols, rows)


def mechanism_csv(rows, m, answer_rows):
    """The ECSS table as rendered (page.top_mechanism.mechanism_rows: each value cell's data-key and
    data-value, its label as text), the interval of the runs below the factor, and the motor answer."""
    out = []
    for label, value in rows:
        hit = DATA.search(value)
        if hit is None:
            continue
        key, v = hit.group(1), hit.group(2)
        unit = "N m" if key in TORQUE_KEYS else "rad/s" if key in SPEED_KEYS else "1"
        out.append([key, plain(label), unit, int(v) if re.fullmatch(r"-?\d+", v) else float(v)])
    lo, hi = m.p_below_ci
    out += [["mech.p_below.ci_lo", "probability of MF < MF required, 95 % Clopper-Pearson interval, low", "1", lo],
            ["mech.p_below.ci_hi", "probability of MF < MF required, 95 % Clopper-Pearson interval, high", "1", hi]]
    out += [list(r) for r in answer_rows]
    return csv_text([("key", ""), ("quantity", ""), ("unit", ""), ("value", "unit")], out)


def bays_csv(table):
    """The per-bay design values (judging.bays.BayTable): one row per bay."""
    cols = [("bay", "1")]
    for f in table.fields:
        u = unit_text(table.units[f])
        cols += [(f"{f} P{table.level:g}", u), (f"{f} upper {100 * table.confidence:g} % bound", u),
                 (f"{f} runs", "1")]
    rows = [[b + 1] + [x for f in table.fields for x in (table.estimate[f][b], table.bound[f][b], table.n[f][b])]
            for b in range(table.n_bays)]
    return csv_text(cols, rows)


def sweep_csv(s):
    """The sweep's per-value table (truss_report.read_sweep): the design value in its unit."""
    names = ["value", "p", "cov", "lower", "upper", "upper_bound", "runs", "no_result", "status",
             "plateau_levels", "refinement"]
    units = s.attrs["units"]
    cols = [(n, unit_text(units.get(n, "1")) if n not in ("status", "refinement") else "") for n in names]
    return csv_text(cols, [[r[n] for n in names] for r in s.to_dict("records")])


def verdict_json(verdict, exit_status, kind, c, items, answer=None):
    """verdict.json: the verdict, its exit status and every item with its status and reason."""
    doc = {"verdict": VERDICT_WORDS[verdict], "exit_status": exit_status, "report": kind,
           "campaign": c.attrs["campaign_name"], "results_file": c.path, "results_sha256": c.sha256,
           "items": [{"item": k, "status": VERDICT_WORDS[s], "reason": r} for k, s, r in items]}
    if answer is not None:
        doc["motor_answer"] = {"load_report_stall_torque_Nm": finite(answer.load.value),
                               "sweep_stall_torque_Nm": finite(answer.sweep.value),
                               "governs": answer.governs or None}
    return json.dumps(doc, indent=2, ensure_ascii=False) + "\n"


def finite(v):
    return float(v) if np.isfinite(v) else None


def names(kind):
    """The export files of a report kind ("load", "sweep")."""
    return ([DESIGN_CSV, STRUCTURE_CSV, MOTOR_CSV, BAYS_CSV] if kind == "load" else [SWEEP_CSV]) + [VERDICT_JSON]

