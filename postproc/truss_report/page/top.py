"""truss_report.page.top: the top of the campaign report: verdict banner, design-load table,
mechanism margins (ECSS), model limits and the sign-off block; the verdict's lines for the
terminal."""
import html
import os
import re

import numpy as np

from ..judging.mechanism import ECSS_SHORT, available_at_speed, screw_speed
from ..judging.verdict import FAIL, NOT_ASSESSED, PASS, VERDICT_WORDS, VerdictItem, verdict_of
from .html import esc, num, table
from .numbers import fmt, fmt_at, resolution, unit_html

RETRACT_TEXT = {
    "braking": "braking: in a retraction the diagonals drive the mast inwards and the drive brakes it (its work is "
               "negative); whether the motor and the screw can brake the peak drive torque of the design loads is not "
               "in the file",
    "holding": "holding: the torque that holds the mast at rest anywhere along the retraction (a brake, the motor's "
               "detent or holding torque) is not in the file",
    "back-drive": "back-drive: whether the mast back-drives the screw and the motor when they are unpowered (the "
                  "screw's backward efficiency, whether it is self-locking) is not in the model"}


def item_html(item: VerdictItem, m):
    """(data-item key, HTML) of a verdict item."""
    if item.what == "margin":
        return "margin", (f"motorisation factor below the required {fmt(m.mf_required)} in "
                          + num("verdict.mf_n_below", item.count, tag="span") + f" of {item.of} ok runs "
                          "(smallest " + num("verdict.mf_min", item.value, digits=3, tag="span") + ")")
    if item.what in ("margin_missing", "margin_undeclared"):
        return item.what.replace("_", "."), f"motorisation not assessed: {esc(item.name)}"
    if item.what == "margin_unjudged":
        return "margin.unjudged", (f"motorisation not assessed in {num('verdict.mf_unjudged', item.count, tag='span')}"
                                   f" of {item.of} ok runs: they hold no finite resistance or available torque")
    if item.what == "status":
        name, k = item.name, item.count
        return f"status.{name}", (num(f"verdict.status.{name}", k, tag="span")
                                  + f" of {item.of} runs <b>{esc(name)}</b> ("
                                  + num(f"verdict.status.{name}.fraction", k / item.of, digits=3, tag="span")
                                  + ")" + ("" if item.kind == FAIL else ": these runs gave no result"))
    if item.what == "nominal":
        return "nominal", f"the nominal run is <b>{esc(item.name)}</b>"
    if item.what == "too_few":
        p = f"p{fmt(item.level)}"
        return f"too_few.{p}", ("too few runs for the design loads: P" + fmt(item.level)
                                + " has no upper confidence bound from "
                                + num(f"verdict.too_few.{p}.n", item.count, tag="span")
                                + " ok runs; it needs ≥ " + num(f"verdict.too_few.{p}", item.needed, tag="span")
                                + " ok runs")
    if item.what == "load_missing":
        return f"load_missing.{item.name}", (num(f"verdict.load_missing.{item.name}", item.count, tag="span")
                                             + f" of {item.of} ok runs have no value of the {esc(item.name)}: "
                                             "its design load is not assessed")
    if item.what == "no_loads":
        return "no_loads", "no design load: no ok run has a value of any load"
    if item.what == "structure":
        return f"structure.{item.name}", (f"structural margin of the {esc(item.name.replace('_', ' '))} below zero "
                                          "(smallest MoS " + num(f"verdict.structure.{item.name}", item.value,
                                                                 digits=3, tag="span") + ")")
    if item.what == "structure_missing":
        return "structure.missing", (f"structural margins not assessed for {esc(item.name.replace('_', ' '))}: no "
                                     "allowable declared in the scene's [structure] table, or no design load")
    if item.what == "retract":
        return f"retract.{item.name}", esc(RETRACT_TEXT[item.name])
    return "check", f"consistency check failed: {esc(item.name)}"


def drive_text(c, m, units):
    """What the campaign is judged against: the drive and its motor, in words (HTML-free)."""
    drive = c.drive
    lab, f = units.get("torque", "Nm")
    if m.mode == "velocity":
        omega = m.omega if np.isfinite(m.omega) else screw_speed(drive)
        speed = f"velocity drive at {fmt(float(drive.get('speed_m_per_s', np.nan)))} m/s"
        if m.undeclared:
            return (f"{speed} (screw speed {fmt(omega)} rad/s); no motor: the campaign declares none, so no "
                    "motor is judged")
        avail = m.t_avail_min if np.isfinite(m.t_avail_min) else available_at_speed(c, drive)
        return (f"{speed} by the scene's motor: stall torque {fmt(m.stall_scene / f)} {lab}, no-load "
                f"speed {fmt(m.no_load_speed)} rad/s (it gives {units.text('torque', 'Nm', avail)} at the "
                f"screw speed {fmt(omega)} rad/s)")
    if m.mode == "motor":
        dispersed = [d.key for d in c.dispersions if d.key.startswith("drive.")]
        return (f"motor drive by a motor of stall torque {fmt(m.stall_scene / f)} {lab}, no-load "
                f"speed {fmt(m.no_load_speed)} rad/s"
                + (f" (base scene; dispersed per run: {', '.join(dispersed)})" if dispersed else ""))
    return f"{m.mode} drive: no motor to judge"


def verdict_html(c, m, items, n_checks, units=None):
    verdict = verdict_of(items)
    judged = m.n > 0 and not (m.missing or m.undeclared)
    checked = (f"checked: motorisation factor ≥ {fmt(m.mf_required)} ({esc(ECSS_SHORT)}; "
               f"spring factor {fmt(m.k_uncertainty)}"
               + (f", inertial factor {fmt(m.k_inertia)})" if m.mode == "velocity" else ")")
               if judged else f"drive mode {esc(m.mode)}: margins not computed ({esc(m.note)})")
    checked += (f"; outcome of all {c.n} runs; an upper bound of every design load; {n_checks} "
                "consistency checks of the file.")
    against = ("Judged against: " + esc(drive_text(c, m, units)) + ".") if units else ""
    head = {PASS: "nothing fails and every requirement was assessed.",
            FAIL: "the evidence violates a requirement.",
            NOT_ASSESSED: "nothing fails, but the evidence cannot decide every requirement."}
    lists = ""
    for kind, title in ((FAIL, "fails"), (NOT_ASSESSED, "not assessed")):
        mine = [item_html(it, m) for it in items if it.kind == kind]
        if mine:
            lists += (f"<div class='small'><b>{title}:</b></div><ul>"
                      + "".join(f"<li data-item='{esc(k)}' data-kind='{kind}'>{t}</li>"
                                for k, t in mine) + "</ul>")
    return (f"<div class='verdict {verdict}' data-key='verdict' data-value='{verdict}'>"
            f"<b>VERDICT: {VERDICT_WORDS[verdict]}</b> — {head[verdict]}{lists}"
            + (f"<br>{against}" if against and not lists else against)
            + f"<br><span class='small'>{checked}</span></div>")


def cell(key, v, factor, unit_label, at):
    """A number shown in its display unit to 10^at (page.numbers); data-value keeps the SI value."""
    text = f"{fmt_at(v / factor, at)}\u00a0{unit_html(unit_label)}" if np.isfinite(v) else fmt(v)
    return f'<td class="num" data-key="{esc(key)}" data-value="{repr(float(v))}">{text}</td>'


def design_table_html(loads, confidence, sampling, units, n_bays):
    lev = [lv.level for lv in loads[0].levels] if loads else []
    heads = ["load", "definition", "nominal", "mean"]
    for q in lev:
        heads += [f"P{fmt(q)}", f"upper {fmt(confidence * 100)} % bound of P{fmt(q)} (rank k of n)"]
    heads += [f"P{fmt(lev[-1])} / nominal" if lev else "ratio"]
    rows = []
    for d in loads:
        lab, f = units.get(d.key, d.unit)
        at = units.at(d.key)
        row = [f"<b>{esc(d.label)}</b><br><code>{esc(d.key)}</code>",
               f"<small>{esc(d.definition)}</small>",
               cell(f"design.{d.key}.nominal", d.nominal, f, lab, at),
               cell(f"design.{d.key}.mean", d.mean, f, lab, at)]
        for lv in d.levels:
            tag = f"design.{d.key}.p{fmt(lv.level)}"
            row.append(cell(tag, lv.estimate, f, lab, at))
            if lv.rank:
                row.append(cell(tag + ".ucb", lv.bound, f, lab, at)[:-5]
                           + f" <small>(k = <span data-key='{tag}.ucb_rank' data-value="
                           f"'{lv.rank}'>{lv.rank}</span> of {d.n})</small></td>")
            else:
                row.append(f"<td class='num toosmall' data-key='{tag}.ucb' data-value='nan'>"
                           f"n = {d.n} too small (needs ≥ <span data-key='{tag}.ucb_n_needed' "
                           f"data-value='{lv.n_needed}'>{lv.n_needed}</span>)</td>")
        row.append(num(f"design.{d.key}.ratio", d.ratio, at=ratio_resolution(d)))
        rows.append(row)
    return ("<h2 id='design'>Design loads</h2>" + table(heads, rows, "design")
            + design_table_note(loads, confidence, sampling, n_bays))


def ratio_resolution(d):
    """The resolution of a load's top percentile over its nominal: from the bound's distance to
    the estimate, over the nominal (the spread of the runs over it without a bound)."""
    lv = d.levels[-1] if d.levels else None
    if lv is None or not np.isfinite(d.nominal) or d.nominal == 0:
        return None
    unc = (lv.bound - lv.estimate) / abs(d.nominal) if lv.rank else float("nan")
    return resolution([d.ratio, d.min / d.nominal, d.max / d.nominal], unc)


def design_table_note(loads, confidence, sampling, n_bays):
    below = [d.label for d in loads if d.nominal_below_runs and d.key.startswith("peak_")]
    nominal = ("" if not below else
               " <b>Why the nominal lies below the runs</b> (" + esc(", ".join(below)) + "): each "
               "of these is the largest of the bays' values in a run; with every bay dispersed, "
               f"the largest of {n_bays} dispersed values is above the nominal one even though each "
               "bay's mean is nominal, so the dispersed runs, not the nominal, give the design "
               "value.")
    return ("<p class='small'>Over the ok runs with a finite value (n per load). Percentiles: "
            "linear interpolation between order statistics (type 7). The upper bound is the "
            "order statistic x<sub>(k)</sub>, k the smallest rank with "
            "Σ<sub>i&lt;k</sub> C(n,i) p<sup>i</sup>(1−p)<sup>n−i</sup> ≥ "
            f"{fmt(confidence)}: distribution-free, one-sided, for independent runs"
            + (" (not valid for Saltelli sampling)" if sampling == "saltelli" else
               "" if sampling == "monte_carlo" else f" ({esc(sampling)} sampling: usually "
               "conservative)") + "; section 2 shows the same bound. Nominal: the base scene "
            "without dispersions (<code>/nominal</code>); impulses are instantaneous momentum "
            "transfers, reported apart from the smooth peaks." + nominal + "</p>")


def terminal_summary(c, m, loads, items, units, confidence):
    """The verdict and its key figures as plain text lines, for the terminal (the page's numbers,
    by the same rule: page.numbers)."""
    tags = re.compile(r"<[^>]+>")
    verdict = verdict_of(items)
    counts = ", ".join(f"{sum(1 for it in items if it.kind == kind)} {VERDICT_WORDS[kind].lower()}"
                       for kind in (FAIL, NOT_ASSESSED) if any(it.kind == kind for it in items))
    lines = [f"VERDICT: {VERDICT_WORDS[verdict]}" + (f" — {counts}" if counts else " — nothing fails")
             + f" ({c.attrs['campaign_name']}, {c.n} runs, {c.attrs['direction']})"]
    lines += [("  FAIL: " if it.kind == FAIL else "  NOT ASSESSED: ")
              + html.unescape(tags.sub("", item_html(it, m)[1])) for it in items]
    lines.append("  judged against: " + drive_text(c, m, units))
    if m.n > 0 and not (m.missing or m.undeclared):
        torque = units.text
        lines.append(f"  ECSS motorisation factor {fmt(m.mf_required)}: torque needed "
                     f"{torque('torque', 'Nm', m.t_min_design)}, available {torque('torque', 'Nm', m.t_avail_min)} "
                     f"(smallest margin {'+' if m.tm_min > 0 else ''}{fmt_at(100 * m.tm_min, resolution([100 * m.tm_min]))}"
                     f" %); stall torque needed {torque('torque', 'Nm', m.stall_needed)}")
    elif m.undeclared and np.isfinite(m.t_min_design):
        lines.append(f"  ECSS motorisation factor {fmt(m.mf_required)}: torque needed "
                     f"{units.text('torque', 'Nm', m.t_min_design)} at the screws (no motor to compare it with)")
    for d in loads:
        if d.key not in ("peak_drive_force_N", "peak_drive_torque_Nm", "peak_pin_force_N",
                         "deploy_time_s"):
            continue
        lv = d.levels[-1]
        bound = (f"upper {fmt(confidence * 100)} % bound {units.text(d.key, d.unit, lv.bound)}" if lv.rank
                 else f"no bound: n = {d.n} too few, needs ≥ {lv.n_needed}")
        lines.append(f"  {d.label}: P{fmt(lv.level)} {units.text(d.key, d.unit, lv.estimate)} ({bound}), "
                     f"nominal {units.text(d.key, d.unit, d.nominal)}")
    return lines


MODEL_LIMITS = [
    "Rigid bodies: struts, frames and the screw do not deform; only the diagonals are elastic "
    "(linear springs, tension only). No structural modes, so no dynamic amplification of the "
    "loads beyond the rigid-body motion.",
    "Frictionless: pins in the rail, hinges, the screw and the latches have no friction, "
    "hysteresis, harness or adhesion torque. Add them (with their factor 3 of ECSS-E-ST-33-01C "
    "Table 4-2) to the required torque.",
    "Rigid latch: a latch locks instantaneously; the strut's radial kinetic energy is lost in "
    "the impact (peak latch energy), with no latch spring, rebound or load spike. Rail entry "
    "and the start are impulses (momentum jumps) too: their peak force depends on stiffness the "
    "model does not hold, so only their impulses (N s) are reported.",
    "Stack: the stowed bays are held or free as the scene's stack.mode says; a free stack moves "
    "with the lower frame, a held stack does not.",
    "The loads are per mast (drive force and torque: the three screws together) or per pin / per "
    "diagonal as each definition says; "
    "no fatigue, thermal or gravity (orbit: no gravity) effects.",
]


def model_limits_html():
    return ("<h2 id='limits'>Model limits</h2><ul class='limits'>"
            + "".join(f"<li>{esc(t)}</li>" for t in MODEL_LIMITS) + "</ul>")


def signoff_html(revision, path="", sha256=""):
    """The sign-off block: revision, the results file the signatures cover, three rows to sign."""
    rows = [[f"<th>{r}</th>", "", "", ""] for r in ("Prepared", "Checked", "Approved")]
    covers = (f" of the results file <code>{esc(os.path.basename(path))}</code>, SHA-256 "
              f"<code>{esc(sha256)}</code>" if path else "")
    return ("<h2 id='signoff'>Sign-off</h2><p>Revision <b data-key='revision'>"
            f"{esc(revision)}</b>{covers}</p>"
            + table(["", "name", "date", "signature"], rows, "signoff"))


def campaign_doc(c, verdict_html_text):
    """The campaign's rows of the document block."""
    a = c.attrs
    return [("campaign", f"{esc(a['campaign_name'])} ({c.n} runs, {esc(a['direction'])}, "
                         f"{esc(a['drive_mode'])} drive)"),
            ("tool", f"truss {esc(a['software_version'])}, git revision "
                     f"<code>{esc(a['git_revision'])}</code> (wrote the file; "
                     "<code>postproc/report.py</code> of the same repository wrote the report)"),
            ("campaign run (UTC)", f"{esc(a['start_utc'])} to {esc(a['end_utc'])}"),
            ("verdict", verdict_html_text)]
