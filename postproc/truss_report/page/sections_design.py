"""truss_report.page.sections_design: the nominal run, the engineering plots and the assembly of the
campaign report (verdict and design loads on top)."""
from functools import partial

import numpy as np

from ..judging.correlations import top_inputs
from ..judging.sobol import sobol_agreement
from ..judging.motor_answer import LOAD
from ..judging.verdict import EXIT_STATUS, VERDICT_WORDS
from .exports import (BAYS_CSV, DESIGN_CSV, MOTOR_CSV, STRUCTURE_CSV, VERDICT_JSON, bays_csv, design_csv,
                      mechanism_csv, plain, structure_csv, verdict_json)
from .figures_design import (fig_convergence, fig_envelopes, fig_peak_location, fig_scatter,
                             fig_sobol_convergence, input_axis)
from .figures_run import fig5
from .html import esc, html_page, num, table
from .render import Report
from .sections_campaign import section_campaign, section_loads, section_lock_timing
from .sections_free import section_rail_miss
from .sections_margins import (section_checks, section_histories, section_margins,
                               section_sensitivity)
from .numbers import MOST, DisplayUnits, choose_load_units, fmt, message_text
from .motor_answer import motor_answer_html, motor_answer_lines, motor_answer_rows
from .top import (campaign_doc, design_table_html, item_html, model_limits_html, signoff_html, terminal_summary,
                  verdict_html)
from .top_bays import bays_html
from .top_mechanism import mechanism_html, mechanism_rows
from .top_structure import structure_html


def section_nominal(page, e):
    out = ["<section id='nominal'><h2>Nominal run</h2>"]
    if e.nominal is None:
        return out[0] + ("<p class='warn'>This file has no <code>/nominal</code> (written before "
                         "truss-campaign stored the nominal run).</p></section>")
    out.append(f"<p>The base scene without dispersions, computed once: status <b>"
               f"{esc(e.nominal_status)}</b>{(': ' + esc(message_text(e.nominal_message))) if e.nominal_message else ''}."
               " Its values are the nominal column of the design-load table and the black lines "
               "of the histograms.</p>")
    if e.nominal_run is not None:
        out.append(page.figure(partial(fig5, page.plt, e.nominal_run), "nominal_history.png",
                               "nominal run: drive force and rail pin force against time, lock "
                               "times dashed"))
    lock = e.nominal_bays["lock_time_s"]
    n = int(np.sum(np.isfinite(lock)))
    rows = [[str(j + 1), num(f"nominal.lock_time_s.bay{j + 1}", float(lock[j]), "s", digits=MOST)]
            for j in range(n)]
    out.append("<details><summary>lock times of the nominal run</summary>"
               + table(["bay", "lock time"], rows, "narrow") + "</details></section>")
    return "\n".join(out)


def section_plots(page, c, e, j, du, opts):
    out = ["<section id='plots'><h2>Where and how the loads arise</h2>"]
    top = opts.levels[-1]
    fields = [(k, lab, e.bays[k]) for k, lab in
              (("peak_drive_force_N", "peak drive force"), ("peak_pin_force_N", "peak pin force"),
               ("latch_energy_J", "latch energy"), ("entry_impulse_Ns", "rail-entry impulse"),
               ("unlock_impulse_Ns", "unlock impulse"))
              if k in e.bays and np.any(np.isfinite(e.bays[k][c.ok]) & (e.bays[k][c.ok] != 0))]
    if fields:
        units = {k: du.get(k, e.units[k], b[c.ok]) for k, _, b in fields}
        out.append("<h3>Per-bay envelopes</h3>" + page.figure(
            partial(fig_envelopes, page.plt, fields, c.ok, e.nominal_bays if e.nominal is not None else None,
                          units, top), "envelopes.png",
            f"per-bay peak loads over the ok runs: P50, P{top:g}, min–max band, nominal"))
    items = [(lab, e.runs[b], e.runs[t], c.outputs[v], v) for lab, b, t, v in
             (("peak drive force", "peak_drive_force_bay", "peak_drive_force_time_s",
               "peak_drive_force_N"),
              ("peak pin force", "peak_pin_force_bay", "peak_pin_force_time_s", "peak_pin_force_N"))
             if b in e.runs and t in e.runs]
    items = [(lab, np.where(c.ok, b, np.nan), t, v, k) for lab, b, t, v, k in items]
    if items:
        units = {k: du.get(k, c.units[k], v) for _, _, _, v, k in items}
        out.append("<h3>Where the peaks occur</h3>" + page.figure(
            partial(fig_peak_location, page.plt, items, units), "peak_location.png",
            "bay and time of each ok run's peak (top: runs per bay; bottom: value against time)"))
    scatter = subsection_scatter(page, c, j, du) if c.dispersions else ""
    if scatter:
        out.append(scatter)
    series = [(d.label, du.get(d.key, d.unit), c.outputs[d.key][c.ok & np.isfinite(c.outputs[d.key])])
              for d in j.loads if d.key in c.outputs and d.key != "deploy_time_s"]
    if series:
        out.append("<h3>Convergence of the percentile estimates</h3>" + page.figure(
            partial(fig_convergence, page.plt, series, opts.levels, opts.confidence), "convergence.png",
            f"percentile estimates over the first m runs (run-index order) with their one-sided "
            f"{opts.confidence * 100:g} % bounds"))
    if c.sensitivity is not None:
        G = len(c.sensitivity.factor)
        ss = [(k, c.outputs[k], c.ok) for k in ("peak_drive_force_N", "peak_pin_force_N")]
        out.append("<h3>Convergence of the Sobol' indices</h3>" + page.figure(
            partial(fig_sobol_convergence, page.plt, ss, G, c.sensitivity.factor, opts.confidence),
            "sobol_convergence.png", "total Sobol' index of each factor against the blocks "
            "used, recomputed here (Jansen), with a percentile-bootstrap interval over blocks"))
        out.append("<p class='small'>Recomputed from all usable blocks, the indices differ from "
                   f"<code>/sensitivity</code> by at most {fmt(sobol_agreement(c.sensitivity, ss), 2)} (same "
                   "estimators; only the order of the roundings differs).</p>")
    out.append("</section>")
    return "\n".join(out)


def subsection_scatter(page, c, j, du):
    """Each load against its three inputs of largest |Spearman rho| (empty without such a load)."""
    rows, nominal = [], {}
    for d in j.loads:
        if d.impulse or d.key not in c.outputs:
            continue
        y = np.where(c.ok, c.outputs[d.key], np.nan)
        rows.append((d.label, du.get(d.key, d.unit), y,
                     [input_axis(col) for col in top_inputs(j.columns, j.correlations, d.key)]))
        nominal[d.label] = d.nominal
    if not rows:
        return ""
    return ("<h3>Top inputs against each load</h3>" + page.figure(
        partial(fig_scatter, page.plt, rows, nominal), "scatter_top_inputs.png",
        "each load against its three inputs of largest |Spearman ρ| (ok runs), nominal "
        "dashed; an aggregate input (“mean relative deviation over bays”) is the mean "
        "over the run's bays of (value − nominal) / nominal, in %"))


def write_exports(page, c, j, confidence, du, answer):
    """The load report's tables as CSV and its verdict as JSON, beside the page (page.exports)."""
    m = j.margins
    page.text_file(DESIGN_CSV, design_csv(j.loads, confidence))
    page.text_file(STRUCTURE_CSV, structure_csv(j.structure, j.structure_bays))
    page.text_file(MOTOR_CSV, mechanism_csv(mechanism_rows(m, du), m, motor_answer_rows(answer)))
    page.text_file(BAYS_CSV, bays_csv(j.bay_table))
    items = [(key, it.kind, plain(text)) for it in j.items for key, text in [item_html(it, m)]]
    page.text_file(VERDICT_JSON, verdict_json(j.verdict, EXIT_STATUS[j.verdict], "load", c, items, answer))


def campaign_report(page, c, e, j, opts, answer=None):
    """The campaign report (j: its CampaignJudgement; answer: the motor answer with a motor-sizing
    sweep, judging.motor_answer, or None), with the verdict's lines for the terminal."""
    du = DisplayUnits()    # one unit per quantity, chosen from the design loads
    choose_load_units(du, j.loads)
    body = [section_campaign(page, c, j, du), section_rail_miss(c), section_loads(page, c, e, j, du, opts.confidence),
            section_lock_timing(page, c, j.lock), section_margins(page, c, du), section_sensitivity(page, c, j),
            section_histories(page, c)]
    n_checks = 7 if c.histories else 6
    body.append(section_checks(c, j.checks, n_checks))
    m = j.margins
    top = [verdict_html(c, m, j.items, len(j.checks), du),
           design_table_html(j.loads, opts.confidence, c.sampling, du, c.attrs["n_bays_max"]),
           mechanism_html(m, du),
           motor_answer_html(answer, LOAD, *du.get("torque", "Nm"), du.at("torque")),
           structure_html(j.structure, j.structure_bays, opts.levels[-1], opts.confidence, du),
           bays_html(page, j.torque_chart, j.bay_table, c.direction, du)]
    summary = terminal_summary(c, m, j.loads, j.items, du, opts.confidence)
    summary += motor_answer_lines(answer, *du.get("torque", "Nm"), du.at("torque"))
    write_exports(page, c, j, opts.confidence, du, answer)
    rest = [section_nominal(page, e), section_plots(page, c, e, j, du, opts)]
    toc = ("<nav><a href='#design'>Design loads</a> · <a href='#mechanism'>Mechanism margins</a> · "
           "<a href='#motor-answer'>One motor answer</a> · <a href='#structure'>Structural margins</a> · "
           "<a href='#bays'>Motorisation chart, per bay</a> · "
           "<a href='#nominal'>Nominal run</a> · <a href='#plots'>Plots</a> · "
           "1. <a href='#campaign'>Campaign</a> · 2. <a href='#loads'>Peak loads</a> · "
           "3. <a href='#locks'>Lock timing</a> · 4. <a href='#margins'>Margins</a> · "
           "5. <a href='#sensitivity'>What drives the loads</a>"
           + (" · 6. <a href='#histories'>Histories</a>" if c.histories else "")
           + f" · {n_checks}. <a href='#checks'>Consistency</a> · <a href='#limits'>Model "
           "limits</a> · <a href='#signoff'>Sign-off</a></nav>")
    title = f"Load report: campaign “{c.name}”"
    return Report(html_page(title, c.path, c.sha256, "\n".join(top) + toc + "\n".join(rest + body)
                            + model_limits_html() + signoff_html(opts.revision, c.path, c.sha256),
                            campaign_doc(c, f"<b>{VERDICT_WORDS[j.verdict]}</b>")),
                  summary, j.verdict)
