"""truss_report.page.top_bays: the motorisation chart (resistive torque per bay against the motor's
torque after derating and losses) and the per-bay design values (lock time, latch energy, pin
force, rail-entry impulse: the top level's percentile with its upper bound, per bay)."""
from functools import partial

import numpy as np

from .figures_motor import fig_motor_torque
from .html import esc, num, table
from .numbers import DASH, fmt

LABELS = {"lock_time_s": "lock time", "latch_energy_J": "latch energy", "peak_pin_force_N": "peak pin force",
          "entry_impulse_Ns": "rail-entry impulse per pin"}
RETRACT_LABELS = {"lock_time_s": "unlock time", "latch_energy_J": "unlock energy"}


def label(f, direction):
    return (RETRACT_LABELS if direction == "retract" else {}).get(f, LABELS[f])


def chart_html(page, chart, level, du):
    """The chart, or why there is none."""
    if chart is None:
        return ("<p>No motorisation chart: it needs a velocity drive (the prescribed motion makes the drive "
                "force the mast's resistance) and the file's per-bay drive force and available torque.</p>")
    lab, f = du.get("torque", "Nm", chart.resist[np.isfinite(chart.resist)])
    return page.figure(
        partial(fig_motor_torque, page.plt, chart, level, lab, f), "motorisation_chart.png",
        f"resistive torque at the screws per bay (the peak drive torque of the bay's stage, F h / 2π, the three "
        f"screws together): P50, P{fmt(level)} and min–max over the ok runs, nominal dashed; green: the motor's "
        "torque at the prescribed speed delivered to the screws after its derating and the drive train's losses, "
        "N η_g η_s (T_available − T_L)")


def bay_table_html(t, direction, du):
    """One row per bay: per field its P{level} and upper bound (units in the header)."""
    if not t.fields:
        return "<p>No per-bay loads in the file.</p>"
    conf = fmt(100 * t.confidence)
    heads, units = ["bay"], {}
    for fld in t.fields:
        values = np.concatenate([t.estimate[fld], t.bound[fld]])
        values = values[np.isfinite(values)]
        gap = t.bound[fld] - t.estimate[fld]
        gap = gap[np.isfinite(gap) & (gap > 0)]
        du.choose(du.ALIASES.get(fld, fld), t.units[fld], float(np.max(np.abs(values))) if len(values) else np.nan,
                  values, float(np.min(gap)) if len(gap) else np.nan)   # a load's own unit when it has one
        lab, factor = du.get(fld, t.units[fld])
        units[fld] = (lab, factor, du.at(fld))
        heads += [f"{esc(label(fld, direction))}: P{fmt(t.level)} ({esc(lab)})",
                  f"upper {conf} % bound ({esc(lab)})"]
    rows = []
    for b in range(t.n_bays):
        row = [str(b + 1)]
        for fld in t.fields:
            lab, factor, at = units[fld]
            key = f"bays.{fld}.bay{b + 1}"
            row += [num(f"{key}.p", float(t.estimate[fld][b]), factor=factor, at=at),
                    num(f"{key}.ucb", float(t.bound[fld][b]), factor=factor, at=at)]
        rows.append(row)
    note = (f" An upper bound needs at least {t.n_needed} ok runs with a value: with fewer it is {DASH}."
            if t.n_needed else "")
    return (table(heads, rows, "narrow")
            + f"<p class='small'>Per bay over the ok runs with a value: the P{fmt(t.level)} (type 7) and its "
            f"one-sided {conf} % distribution-free upper bound, as the design loads' (the order statistic of "
            f"the smallest rank whose binomial sum reaches {fmt(t.confidence)}).{note}</p>")


def bays_html(page, chart, t, direction, du):
    return ("<h2 id='bays'>Motorisation chart and per-bay design values</h2>" + chart_html(page, chart, t.level, du)
            + "<h3>Per-bay design values</h3>" + bay_table_html(t, direction, du))
