"""truss_report.page.top: the top of the campaign report: verdict banner, design-load table,
mechanism margins (ECSS), model limits and the sign-off block; the verdict's lines for the
terminal."""
import html
import os
import re

import numpy as np

from ..judging.mechanism import (ECSS_CLAUSE, ECSS_CONFIRM, ECSS_SHORT, Margins, available_at_speed,
                                 screw_speed)
from ..judging.verdict import FAIL, NOT_ASSESSED, PASS, VERDICT_WORDS, VerdictItem, verdict_of
from .html import digits_for, esc, fmt, num, table, unit_html


def item_html(item: VerdictItem, m: Margins):
    """(data-item key, HTML) of a verdict item."""
    if item.what == "margin":
        return "margin", (f"motorisation factor below the required {fmt(m.mf_required)} in "
                          + num("verdict.mf_n_below", item.count, tag="span") + f" of {item.of} ok runs "
                          "(smallest " + num("verdict.mf_min", item.value, digits=4, tag="span") + ")")
    if item.what == "margin_missing":
        return "margin.missing", f"mechanism margins not computed: {esc(item.name)}"
    if item.what == "status":
        name, k = item.name, item.count
        return f"status.{name}", (num(f"verdict.status.{name}", k, tag="span")
                                  + f" of {item.of} runs <b>{esc(name)}</b> ("
                                  + num(f"verdict.status.{name}.fraction", k / item.of, digits=4, tag="span")
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
    return "check", f"consistency check failed: {esc(item.name)}"


def drive_text(c, m, units):
    """What the campaign is judged against: the drive and its motor, in words (HTML-free)."""
    drive = c.drive
    lab, f = units.get("torque", "Nm")
    if m.mode == "velocity":
        omega = m.omega if np.isfinite(m.omega) else screw_speed(drive)
        avail = m.t_avail_min if np.isfinite(m.t_avail_min) else available_at_speed(c, drive)
        return (f"velocity drive at {fmt(float(drive.get('speed_m_per_s', np.nan)))} m/s by the "
                f"scene's motor: stall torque {fmt(m.stall_scene / f)} {lab}, no-load "
                f"speed {fmt(m.no_load_speed)} rad/s (it gives {fmt(avail / f)} {lab} at the "
                f"screw speed {fmt(omega, 5)} rad/s)")
    if m.mode == "motor":
        dispersed = [d.key for d in c.dispersions if d.key.startswith("drive.")]
        return (f"motor drive by a motor of stall torque {fmt(m.stall_scene / f)} {lab}, no-load "
                f"speed {fmt(m.no_load_speed)} rad/s"
                + (f" (base scene; dispersed per run: {', '.join(dispersed)})" if dispersed else ""))
    return f"{m.mode} drive: no motor to judge"


def verdict_html(c, m, items, n_checks, units=None):
    verdict = verdict_of(items)
    checked = (f"checked: motorisation factor ≥ {fmt(m.mf_required)} ({esc(ECSS_SHORT)}; "
               f"spring factor {fmt(m.k_uncertainty)}"
               + (f", inertial factor {fmt(m.k_inertia)})" if m.mode == "velocity" else ")")
               if m.n > 0 else f"drive mode {esc(m.mode)}: margins not computed ({esc(m.note)})")
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


def cell(key, v, factor, unit_label, digits=5):
    """A number shown in readable units; data-value keeps the SI value."""
    text = f"{fmt(v / factor, digits)}\u00a0{unit_html(unit_label)}" if np.isfinite(v) else fmt(v)
    return f'<td class="num" data-key="{esc(key)}" data-value="{repr(float(v))}">{text}</td>'


def load_digits(d):
    """Significant digits of a design load's row: enough to show its spread over the runs."""
    return digits_for([d.min, d.max, d.nominal, d.mean] + [lv.estimate for lv in d.levels]
                      + [lv.bound for lv in d.levels], least=4)


def design_table_html(loads, confidence, sampling, units, n_bays):
    lev = [lv.level for lv in loads[0].levels] if loads else []
    heads = ["load", "definition", "nominal", "mean"]
    for q in lev:
        heads += [f"P{fmt(q)}", f"upper {fmt(confidence * 100)} % bound of P{fmt(q)} (rank k of n)"]
    heads += [f"P{fmt(lev[-1])} / nominal" if lev else "ratio"]
    rows = []
    for d in loads:
        lab, f = units.get(d.key, d.unit)
        dg = load_digits(d)
        row = [f"<b>{esc(d.label)}</b><br><code>{esc(d.key)}</code>",
               f"<small>{esc(d.definition)}</small>",
               cell(f"design.{d.key}.nominal", d.nominal, f, lab, dg),
               cell(f"design.{d.key}.mean", d.mean, f, lab, dg)]
        for lv in d.levels:
            tag = f"design.{d.key}.p{fmt(lv.level)}"
            row.append(cell(tag, lv.estimate, f, lab, dg))
            if lv.rank:
                row.append(cell(tag + ".ucb", lv.bound, f, lab, dg)[:-5]
                           + f" <small>(k = <span data-key='{tag}.ucb_rank' data-value="
                           f"'{lv.rank}'>{lv.rank}</span> of {d.n})</small></td>")
            else:
                row.append(f"<td class='num toosmall' data-key='{tag}.ucb' data-value='nan'>"
                           f"n = {d.n} too small (needs ≥ <span data-key='{tag}.ucb_n_needed' "
                           f"data-value='{lv.n_needed}'>{lv.n_needed}</span>)</td>")
        row.append(num(f"design.{d.key}.ratio", d.ratio, digits=max(4, dg)))
        rows.append(row)
    return ("<h2 id='design'>Design loads</h2>" + table(heads, rows, "design")
            + design_table_note(loads, confidence, sampling, n_bays))


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


def mechanism_html(m, units):
    """The ECSS table. With no resistance in the file (m.missing) the table is still shown, its
    values "—" and a footnote saying why; with no resistance to overcome, a sentence."""
    head = f"<h2 id='mechanism'>Mechanism margins ({esc(ECSS_SHORT)})</h2>"
    if m.n == 0 and not m.missing:
        return head + f"<p>Not computed: {esc(m.note)}.</p>"
    lab, f = units.get("torque", "Nm")
    rows = mechanism_rows(m, lab, f)
    if m.missing:    # counts of runs would read as results: shown as "—" too
        rows = [[a, "<td class='num'>—</td>" if "data-key=\"mech.n" in b else b] for a, b in rows]
    note = (f"<p class='small'>— : {esc(m.note)}; these margins are not assessed.</p>"
            if m.missing else "")
    return (head + mechanism_text(m) + table(["", "value"], [[f"<th>{a}</th>", b] for a, b in rows],
                                            "kv") + note)


def mechanism_rows(m, lab, f):
    """[(label html, value cell)] of the ECSS table (torques shown in lab = SI / f)."""
    lo, hi = m.p_below_ci
    vel = m.mode == "velocity"
    avail = ("the scene's motor at the prescribed screw speed" if vel else
             "the motor's stall torque (per run when dispersed)")
    rows = [
        ["required motorisation factor MF (option --motorisation-factor)",
         num("mech.mf_required", m.mf_required)],
        ["uncertainty factor k<sub>S</sub> on the spring resistance S (--uncertainty-factor; "
         "Table 4-2: spring 1.2)", num("mech.k_uncertainty", m.k_uncertainty)],
        ["factor k<sub>D</sub> on the inertial resistance T<sub>D</sub> (--inertia-factor; "
         "equation: 1.25)" + ("" if vel else ": T<sub>D</sub> = 0 in motor mode"),
         num("mech.k_inertia", m.k_inertia)],
        ["runs considered (ok, finite positive S)", num("mech.n", m.n)],
        ["largest spring resistance S (peak static torque)", cell("mech.s_design", m.s_design, f, lab)],
        ["largest inertial resistance T<sub>D</sub> (peak drive − static torque)",
         cell("mech.d_design", m.d_design, f, lab)],
        ["largest T<sub>min</sub> = MF k<sub>S</sub> S + k<sub>D</sub> T<sub>D</sub>",
         cell("mech.t_min", m.t_min_design, f, lab)],
        [f"smallest available torque ({avail})", cell("mech.t_avail_min", m.t_avail_min, f, lab)],
        ["smallest achieved MF = (T<sub>available</sub> − k<sub>D</sub> T<sub>D</sub>) / "
         "(k<sub>S</sub> S)", num("mech.mf_min", m.mf_min, digits=4)],
        ["smallest torque margin T<sub>available</sub> / T<sub>min</sub> − 1",
         num("mech.tm_min", m.tm_min, digits=4)],
        ["achieved MF of the nominal run", num("mech.mf_nominal", m.mf_nominal, digits=4)],
        ["runs with MF < MF required", num("mech.n_below", m.n_below)],
        ["probability, 95 % Clopper-Pearson interval",
         f"<td class='num'>[{fmt(lo, 4)}, {fmt(hi, 4)}]</td>"],
    ]
    if vel:
        rows += [["screw speed ω = 2π v / h", num("mech.omega", m.omega, "rad/s")],
                 ["no-load speed ω<sub>0</sub> of the scene's motor",
                  num("mech.omega0", m.no_load_speed, "rad/s")]]
    rows += [["<b>stall torque needed</b>" + (" (with that ω<sub>0</sub>: T<sub>min</sub> / "
                                               "(1 − ω/ω<sub>0</sub>))" if vel else ""),
              cell("mech.stall_needed", m.stall_needed, f, lab)],
             ["stall torque of the scene's motor", cell("mech.stall_scene", m.stall_scene, f, lab)]]
    return rows


def mechanism_text(m):
    """The clause's equation and what of it this model holds, with the source."""
    vel = m.mode == "velocity"
    return ("<p>T<sub>min</sub> = 2 (1.1 I + 1.2 S + 1.5 H<sub>M</sub> + 3 F<sub>R</sub> + "
            "3 H<sub>Y</sub> + 3 H<sub>A</sub> + 3 H<sub>D</sub>) + 1.25 T<sub>D</sub> + "
            "T<sub>L</sub> (clause 4.7.5.3.1; uncertainty factors of Table 4-2, theoretical "
            "column). Torques are at the screws, the three together: the torque of one motor "
            "that drives them 1:1 (one screw carries a third). This rigid, frictionless model has "
            "the spring resistance S (the diagonals: the torque that holds the mast at rest along "
            "its path)"
            + (" and, with the prescribed speed as the acceleration requirement, the inertial "
               "resistance T<sub>D</sub> (drive torque minus S). " if vel else
               "; the motor drive has no specified acceleration, so T<sub>D</sub> = 0 and the "
               "motor's stall torque is compared with the factored springs. ")
            + "Each is its peak over the run, so T<sub>min</sub> is an upper bound. I, "
            "H<sub>M</sub>, F<sub>R</sub>, H<sub>Y</sub>, H<sub>A</sub>, H<sub>D</sub> and "
            "T<sub>L</sub> are zero in the model: friction, hysteresis, harness and adhesion "
            "(factor 3) must be added by the user.</p><p class='small'>Source: "
            f"{esc(ECSS_CLAUSE)}. {esc(ECSS_CONFIRM)}</p>")


def qty(v, lab, digits=5):
    """A value with its unit in plain text; "—" alone when it does not apply."""
    return f"{fmt(v, digits)} {lab}" if np.isfinite(v) else fmt(v)


def terminal_summary(c, m, loads, items, units, confidence):
    """The verdict and its key figures as plain text lines, for the terminal."""
    tags = re.compile(r"<[^>]+>")
    verdict = verdict_of(items)
    counts = ", ".join(f"{sum(1 for it in items if it.kind == kind)} {VERDICT_WORDS[kind].lower()}"
                       for kind in (FAIL, NOT_ASSESSED) if any(it.kind == kind for it in items))
    lines = [f"VERDICT: {VERDICT_WORDS[verdict]}" + (f" — {counts}" if counts else " — nothing fails")
             + f" ({c.attrs['campaign_name']}, {c.n} runs, {c.attrs['direction']})"]
    lines += [("  FAIL: " if it.kind == FAIL else "  NOT ASSESSED: ")
              + html.unescape(tags.sub("", item_html(it, m)[1])) for it in items]
    lines.append("  judged against: " + drive_text(c, m, units))
    if m.n > 0:
        lab, f = units.get("torque", "Nm")
        lines.append(f"  ECSS motorisation factor {fmt(m.mf_required)}: torque needed "
                     f"{qty(m.t_min_design / f, lab)}, available {qty(m.t_avail_min / f, lab)} "
                     f"(smallest margin {m.tm_min * 100:+.1f} %); stall torque needed "
                     f"{qty(m.stall_needed / f, lab)}")
    for d in loads:
        if d.key not in ("peak_drive_force_N", "peak_drive_torque_Nm", "peak_pin_force_N",
                         "deploy_time_s"):
            continue
        lab, f = units.get(d.key, d.unit)
        lv = d.levels[-1]
        dg = load_digits(d)
        bound = (f"upper {confidence * 100:g} % bound {qty(lv.bound / f, lab, dg)}" if lv.rank
                 else f"no bound: n = {d.n} too few, needs >= {lv.n_needed}")
        lines.append(f"  {d.label}: P{fmt(lv.level)} {qty(lv.estimate / f, lab, dg)} ({bound}), "
                     f"nominal {qty(d.nominal / f, lab, dg)}")
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
