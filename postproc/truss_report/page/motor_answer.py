"""truss_report.page.motor_answer: the one motor answer on the load report and on the motor-sizing
sweep's page alike (judging.motor_answer): both needed stall torques with their statistical basis
and file, which one governs and why, the scene check that made them comparable; its terminal
lines and its rows for motorisation.csv."""
import os

import numpy as np

from ..judging.motor_answer import LOAD, SWEEP, SIZING_FAILURE
from .html import esc, num, table
from .numbers import DASH, fmt, fmt_at, message_text

NAMES = {LOAD: "load report", SWEEP: "motor-sizing sweep"}
WHY_LARGER = ("a motor must meet both criteria, and each only gets easier as the stall torque grows, so the "
              "larger needed stall torque meets both")


def basis_text(a, which):
    """The statistical basis of one figure, in words."""
    f = a.load if which == LOAD else a.sweep
    if which == LOAD:
        return (f"upper {fmt(100 * f.confidence)} % confidence bound of the P{fmt(f.level)} of the runs' stall "
                "torque that meets the ECSS motorisation factors (the load report's dispersions)")
    return (f"smallest stall torque whose one-sided {fmt(100 * f.confidence)} % upper bound on "
            f"P({SIZING_FAILURE} ≤ 0) is at most {fmt(f.target)} (the sweep's dispersions)")


def torque_text(v, lab, factor, at):
    return f"{fmt_at(v / factor, at)} {lab}" if np.isfinite(v) else DASH


def governs_text(a, lab, factor, at):
    """The sentence on which figure governs (plain text)."""
    if not a.governs:
        missing = [f"the {NAMES[w]} gives none ({message_text(f.why)})"
                   for w, f in ((LOAD, a.load), (SWEEP, a.sweep)) if not np.isfinite(f.value)]
        return "Which figure governs cannot be said: " + "; ".join(missing) + "."
    v = a.governing_value
    own = ""
    if np.isfinite(a.own_value):
        own = (f" The scene's motor, {torque_text(a.own_value, lab, factor, None)}, is "
               + ("at or above" if a.own_value >= v else "below") + " it.")
    return f"The {NAMES[a.governs]}'s {torque_text(v, lab, factor, at)} governs: {WHY_LARGER}.{own}"


def missing_html(here):
    other = SWEEP if here == LOAD else LOAD
    arg = "SWEEP.h5" if here == LOAD else "RESULTS.h5"
    return ("<h2 id='motor-answer'>One motor answer</h2><p data-key='motor_answer.governs' data-value='none'>"
            f"The {NAMES[other]}'s needed stall torque is not shown, so which figure governs is not said: "
            f"give its file with <code>--compare-with {arg}</code> (the same mast; docs/report.md).</p>")


def motor_answer_html(a, here, lab, factor, at):
    """The section on the page of `here` (LOAD or SWEEP); torques in (lab, factor) to 10^at."""
    if a is None:
        return missing_html(here)
    rows = []
    for which, f in ((LOAD, a.load), (SWEEP, a.sweep)):
        this = " (this report)" if which == here else ""
        value = num(f"motor_answer.{which}", f.value, lab, factor=factor, at=at)
        rows.append([f"<b>{NAMES[which]}</b>{this}", value, esc(basis_text(a, which))
                     + (f"; — : {esc(message_text(f.why))}" if f.why else ""),
                     f"<code>{esc(os.path.basename(f.file))}</code><br><small>SHA-256 "
                     f"<code>{esc(f.sha256[:16])}…</code></small>"])
    disp = "; ".join(f"dispersed only in the {NAMES[w]}: {', '.join(keys)}"
                     for w, keys in ((LOAD, a.only_load), (SWEEP, a.only_sweep)) if keys)
    replaced = (" The report's options replace the scene's motorisation factors for the load report's figure; "
                "the sweep's margin used the scene's." if a.factors_replaced else "")
    return ("<h2 id='motor-answer'>One motor answer: the load report and the motor-sizing sweep</h2>"
            + table(["campaign", "stall torque needed", "statistical basis", "file"], rows)
            + f"<p data-key='motor_answer.governs' data-value='{a.governs or 'none'}'>"
            + esc(governs_text(a, lab, factor, at)) + "</p>"
            + f"<p class='small'>The same mast: the base scenes agree on all {a.n_compared} keys compared (all but "
            "the swept stall torque, keys drawn absolutely, [structure] and the integrator's [run] settings). "
            + (esc(disp[0].upper() + disp[1:]) + ". " if disp else "")
            + "The figures differ where the campaigns scatter different inputs or state different probabilities."
            + replaced + "</p>")


def motor_answer_lines(a, lab, factor, at):
    """The terminal's lines."""
    if a is None:
        return []
    return [f"  motor answer: load report {torque_text(a.load.value, lab, factor, at)}, motor-sizing sweep "
            f"{torque_text(a.sweep.value, lab, factor, at)}. " + governs_text(a, lab, factor, at)]


def motor_answer_rows(a):
    """(key, quantity, unit, value) rows for motorisation.csv (N m, full precision)."""
    if a is None:
        return []
    return [("motor_answer.load_report", "stall torque needed, load report: " + basis_text(a, LOAD), "N m",
             a.load.value),
            ("motor_answer.sweep", "stall torque needed, motor-sizing sweep: " + basis_text(a, SWEEP), "N m",
             a.sweep.value),
            ("motor_answer.governs", "the figure that governs (the larger)", "", a.governs or "none")]

