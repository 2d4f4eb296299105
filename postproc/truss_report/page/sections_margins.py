"""truss_report.page.sections_margins: the margins of the drive against its motor, what drives the
loads (rank correlations, tornado charts, Sobol' indices), the runs' histories and the
consistency checks of the file."""
from functools import partial

import numpy as np

from ..judging.correlations import (correlated_factors, outside_unit_interval, proportional_to,
                                    ranked_inputs)
from ..judging.runs import TORQUE_RTOL, motor_exceedance, velocity_exceedance
from ..judging.stats import AGREE_RTOL
from ..reading.schema import OUTPUTS
from .figures import fig_motor, fig_sobol, fig_tornado, fig_velocity_margin
from .figures_run import fig5
from .html import esc, num, table
from .numbers import fmt, fmt_at, p_digits, resolution, uncertainty_resolution
from .sections_campaign import output_label

TORNADO_TOP = 15
MAX_HISTORY_FIGURES = 12


def probability_rows(key, label, p, lo, hi):
    """A probability and its 95 % Clopper-Pearson interval, each a row (page.numbers, rule 3)."""
    d = p_digits(p, lo, hi)
    return [[label, num(key, p, digits=d)], ["95 % Clopper-Pearson interval, low", num(f"{key}.ci_lo", lo, digits=d)],
            ["95 % Clopper-Pearson interval, high", num(f"{key}.ci_hi", hi, digits=d)]]


def rho_at(n):
    """The resolution of a rank correlation over n pairs: two digits of its standard error 1/sqrt(n - 1)."""
    return uncertainty_resolution(1.0 / np.sqrt(max(n - 1, 1)))


def sobol_at(o, g):
    """The resolution of factor g's Sobol' indices: two digits of the half width of its total
    index's interval."""
    return uncertainty_resolution((o.indices["total_hi"][g] - o.indices["total_lo"][g]) / 2.0)


def section_margins(page, c, units):
    head = '<section id="margins"><h2>4. Margins: drive torque against the motor stall torque</h2>'
    if c.attrs["drive_mode"] == "velocity":
        return section_margins_velocity(page, c, units, head)
    if c.attrs["drive_mode"] != "motor":
        return (head + f"<p>The drive mode is <b>{esc(c.attrs['drive_mode'])}</b>: the drive "
                "applies a prescribed torque, there is no motor to compare with.</p></section>")
    torque = c.outputs["peak_drive_torque_Nm"]
    u, f = units.get("torque", c.units["peak_drive_torque_Nm"], torque)
    stall_t = c.stall_torque
    source = ("dispersed: per run from <code>/runs/inputs/drive.stall_torque_Nm</code>"
              if c.stall_torque_dispersed else
              "not dispersed: <code>drive.stall_torque_Nm</code> of the base scene")
    x = motor_exceedance(c)
    if x is None:
        return head + "<p>No ok or stalled run: nothing to compare.</p></section>"
    ok_t, stalled, n_cons, k, lo, hi = x.ok_t, x.stalled, x.n_considered, x.k, x.lo, x.hi
    p = k / n_cons
    nominal = float(c.drive.get("stall_torque_Nm", float("nan")))
    fig = partial(fig_motor, page.plt, torque / f, stall_t / f, ok_t, stalled, nominal / f, u)
    rows = [
        ["stall torque of the base scene", num("motor.stall_torque_nominal", nominal, u, factor=f)],
        ["runs considered (ok with a finite peak torque, + stalled)", num("motor.n_considered",
                                                                         n_cons)],
        ["stalled runs (status stall)", num("motor.n_stall", int(stalled.sum()))],
        ["ok runs with peak torque > stall torque", num("motor.n_ok_exceed", x.n_ok_exceed)],
        ["exceedances", num("motor.n_exceed", k)],
        *probability_rows("motor.p_exceed", "probability of exceeding the stall torque", p, lo, hi),
        ["largest peak torque / stall torque of an ok run",
         num("motor.utilisation_max", x.utilisation_max, at=resolution([x.utilisation_max, 1.0]))],
    ]
    excluded = x.n_other_failures
    return (head + f"<p>Stall torque: {source}. A run exceeds the stall torque when it stalled "
            "(status <code>stall</code>: the motor could not drive the mast, so the torque the "
            "mast needed exceeded what the motor gives; <b>stalled runs count as exceedances</b>) "
            f"or when its peak torque is above its stall torque × (1 + {fmt(TORQUE_RTOL)}). "
            "The motor gives its stall torque at zero speed, at the start, so in an ok run the "
            "peak torque equals the stall torque up to rounding. The probability is exceedances / "
            "runs considered, with an exact (Clopper-Pearson) 95 % interval; the "
            + num("motor.n_other_failures", excluded, tag="span")
            + " runs that failed for another reason are not counted.</p>"
            + page.figure(fig, "motor_torque_margin.png",
                          "stall torque of the ok and stalled runs, and peak drive torque against "
                          "stall torque")
            + table(["", "value"], rows, "narrow") + "</section>")


def section_margins_velocity(page, c, units, head):
    torque = c.outputs["peak_drive_torque_Nm"]
    u, f = units.get("torque", c.units["peak_drive_torque_Nm"], torque)
    if c.motor_declared_by == "":
        return (head + "<p>The campaign declares no motor: the velocity drive prescribes the motion, and the "
                "scene's <code>drive.stall_torque_Nm</code> and <code>drive.no_load_speed_rad_per_s</code> are "
                "defaults the campaign does not set, so no motor is compared with the torque the runs need (their "
                "peak drive torque is in the design loads). Declare the motor in the campaign's "
                "<code>[scene.drive]</code> to compare it.</p></section>")
    if c.motor_torque_at_speed is None:
        return (head + "<p>This file has no <code>/runs/motor_torque_at_speed_Nm</code> (it was "
                "written before the simulator stored the motor's torque at the prescribed speed): "
                "the available torque is not in the file, so this margin is not computed.</p></section>")
    x = velocity_exceedance(c)
    if x is None:
        return head + "<p>No ok run with a finite peak torque: nothing to compare.</p></section>"
    n_cons, k, lo, hi, omega, drive = x.n_considered, x.k, x.lo, x.hi, x.omega, c.drive
    fig = partial(fig_velocity_margin, page.plt, torque[x.considered] / f, x.avail_min / f, x.avail_max / f, u,
                              units.at("torque"))
    ratio_at = resolution([x.ratio_min, x.ratio_p50])
    rows = [
        ["motor stall torque of the scene", num("velmargin.stall_torque", float(drive["stall_torque_Nm"]), u, factor=f)],
        ["motor no-load speed of the scene", num("velmargin.no_load_speed", float(drive["no_load_speed_rad_per_s"]), "rad/s")],
        ["screw speed the prescribed drive speed needs", num("velmargin.required_speed", omega, "rad/s")],
        ["runs considered (ok, finite peak torque)", num("velmargin.n_considered", n_cons)],
        ["runs whose peak torque exceeds the available torque", num("velmargin.n_exceed", k)],
        *probability_rows("velmargin.p_exceed", "probability of exceeding", k / n_cons, lo, hi),
        ["smallest available / peak torque", num("velmargin.ratio_min", x.ratio_min, at=ratio_at)],
        ["median available / peak torque", num("velmargin.ratio_p50", x.ratio_p50, at=ratio_at)],
    ]
    return (head + "<p>Velocity drive: the driven frame follows the prescribed speed whatever torque that "
            "takes, so the campaign gives the <b>torque a motor must deliver</b> (at the screws, the "
            "three together: the torque of one motor driving them 1:1). It is compared with "
            "the scene's motor (<code>drive.stall_torque_Nm</code>, "
            "<code>drive.no_load_speed_rad_per_s</code>) "
            "on its linear speed-torque line: at the screw speed &omega; = 2&pi; v / h the motor gives "
            "T<sub>s</sub> (1 &minus; &omega; / &omega;<sub>0</sub>), per run when any of these is "
            "dispersed. A run exceeds when its peak drive torque is above that; the probability has an "
            "exact (Clopper-Pearson) 95 % interval. This is the bare torque balance, without the "
            "factors of the standard (those are in the mechanism margins at the top). A result of 1 "
            "means this motor cannot hold the prescribed speed at all.</p>"
            + page.figure(fig, "velocity_torque_margin.png",
                          "peak drive torque of the ok runs against the torque the scene's motor gives at the "
                          "prescribed speed")
            + table(["", "value"], rows, "narrow") + "</section>")


def section_sensitivity(page, c, j):
    out = ['<section id="sensitivity"><h2>5. What drives the loads</h2>']
    if not c.dispersions:
        return out[0] + "<p>No dispersed input.</p></section>"
    cols, rho = j.columns, j.correlations
    out.append("<p>Spearman rank correlation ρ (<code>scipy.stats.spearmanr</code>) of each "
               "sampled input with each output, over the ok runs where both are finite. A per-bay "
               "(per-frame) dispersion contributes one input per bay (frame), "
               "<code>key[bay j]</code> (<code>key[frame k]</code>, frame 0 = base), and an "
               "aggregate: the mean over the run's bays (frames) of the relative deviation from "
               "the nominal. Each tornado shows the "
               f"{TORNADO_TOP} inputs with the largest |ρ|; aggregates are hatched. The grey band "
               "is ±1.96/√(n−1), n = the ok runs with a finite output: |ρ| inside it is what "
               "independent inputs give 95 % of the time, for one input taken alone. ρ is "
               "dimensionless.</p>")
    agg_labels = [col.label for col in cols if col.aggregate]
    rows = [[f"<code>{esc(lab)}</code>"] + [num(f"spearman.{k}.{lab}", rho[k][lab][0], at=rho_at(rho[k][lab][1]))
                                            for k in OUTPUTS] for lab in agg_labels]
    out.append("<h3>Rank correlation of every dispersion (aggregates)</h3>"
               + table(["input"] + [f"<code>{k}</code>" for k in OUTPUTS], rows, "corr"))
    figs = []
    aggregate = {col.label for col in cols if col.aggregate}
    proportional = proportional_to(c)
    for key in OUTPUTS:
        if key in proportional:
            figs.append(f"<div class='cell'><p class='note'><code>{key}</code> is proportional to "
                        f"<code>{proportional[key]}</code> in every ok run (same ranks): its "
                        "tornado is that one.</p></div>")
            continue
        ranked = ranked_inputs(rho, key, TORNADO_TOP)
        if not ranked:
            figs.append(f"<div class='cell'><p class='note'><code>{key}</code>: no input "
                        "correlation defined (no finite ok value, or a constant output).</p></div>")
            continue
        n_y = int(np.sum(c.ok & np.isfinite(c.outputs[key])))
        fig = partial(fig_tornado, page.plt, ranked, aggregate, f"{output_label(key, c.direction)} (n = {n_y})",
                          1.96 / np.sqrt(max(n_y - 1, 1)))
        detail = table(["input", "ρ", "runs"],
                       [[f"<code>{esc(lab)}</code>", num(f"spearman.{key}.{lab}", r, at=rho_at(n)),
                         num(f"spearman.{key}.{lab}.n", n)] for lab, r, n in ranked], "narrow")
        figs.append("<div class='cell'>" + page.figure(fig, f"tornado_{key}.png",
                                                         f"Spearman ρ with {key}", "half")
                    + f"<details><summary>values</summary>{detail}</details></div>")
    out.append("<h3>Tornado charts</h3><div class='grid'>" + "".join(figs) + "</div>")
    if c.sensitivity is not None:
        out.append(subsection_sobol(page, c))
    elif c.attrs["sampling"] == "saltelli":
        out.append("<p class='warn'>Saltelli sampling, but the file has no /sensitivity.</p>")
    out.append("</section>")
    return "\n".join(out)


def subsection_sobol(page, c):
    s = c.sensitivity
    factors = s.factor
    outs = s.outputs
    meth = outs[next(iter(outs))]
    parts = ["<h3>Sobol' indices (Saltelli sampling)</h3>",
             "<p>From <code>/sensitivity</code>, as the campaign computed them: method "
             f"“{esc(meth.method)}”, {fmt(meth.confidence, 3)} confidence intervals from "
             f"{meth.n_resamples} bootstrap resamples. A factor is a whole dispersion "
             "(a per-bay "
             "dispersion moves all its bays together). Indices are dimensionless.</p>",
             out_of_range_note(outs),
             design_correlation_note(c, len(factors)),
             page.figure(partial(fig_sobol, page.plt, factors, outs), "sobol_indices.png",
                         "first-order and total Sobol' indices with their confidence intervals")]
    cells = []
    for key, o in outs.items():
        rows = [[f"<code>{esc(fac)}</code>"]
                + [num(f"sobol.{key}.{fac}.{k}", float(o.indices[k][g]), at=sobol_at(o, g))
                   for k in ("first_order", "first_order_lo", "first_order_hi",
                             "total", "total_lo", "total_hi")] for g, fac in enumerate(factors)]
        cells.append(f"<div class='cell'><h4><code>{key}</code></h4><p>blocks used "
                     f"{num(f'sobol.{key}.n_blocks', o.n_blocks, tag='span')}, dropped "
                     f"{num(f'sobol.{key}.n_blocks_dropped', o.n_blocks_dropped, tag='span')}"
                     "</p>" + table(["factor", "S1", "S1 low", "S1 high", "ST", "ST low",
                                     "ST high"], rows, "narrow") + "</div>")
    parts.append("<div class='grid'>" + "".join(cells) + "</div>")
    return "\n".join(parts)


def design_correlation_note(c, n_factors):
    """A warning naming the factors whose A and B columns correlate by more than 4 / sqrt(N)
    (four standard deviations of the correlation of N independent pairs)."""
    bad, limit, n_blocks = correlated_factors(c, n_factors)
    if not bad:
        return ""
    return ("<p class='warn'>Design check: the A and B samples of "
            + ", ".join(f"<code>{esc(k)}</code> (rank correlation {fmt_at(r, rho_at(n_blocks))})"
                        for k, r in sorted(bad.items()))
            + f" are correlated beyond 4/&radic;N = {fmt(limit, 2)} (N = {n_blocks} blocks). Saltelli's "
              "estimators assume them independent: these factors' indices may be biased at this N "
              "(files of schema_version 1 drew A and B from one Sobol' point, whose high dimensions "
              "do this; docs/campaigns.md). Run more blocks before relying on them.</p>")


def out_of_range_note(outs):
    """A warning when point estimates fall outside [0, 1]: the estimators are unbiased, not
    bounded, and such values mean too few blocks for that output."""
    bad = outside_unit_interval(outs)
    if not bad:
        return ""
    return ("<p class='warn'>Some estimates lie outside [0, 1] ("
            + ", ".join(f"<code>{k}</code>" for k in bad)
            + "): the estimators are unbiased but not bounded, so such values mean that the "
              "blocks are too few for that output. Read the confidence intervals, or run more "
              "blocks.</p>")


def section_histories(page, c):
    if not c.histories:
        return ""
    shown = list(c.histories)[:MAX_HISTORY_FIGURES]
    parts = ['<section id="histories"><h2>6. Time histories of selected runs</h2>',
             "<p>From <code>/histories/run_&lt;i&gt;</code> (the campaign's "
             "<code>[output] history_runs</code>): drive force and rail pin force against time, "
             "lock times dashed (as paper Fig. 5).</p>"]
    if len(c.histories) > len(shown):
        parts.append(f"<p>(the first {len(shown)} of {len(c.histories)} histories)</p>")
    for i in shown:
        parts.append(page.figure(partial(fig5, page.plt, c.histories[i]), f"history_run_{i}.png",
                                 f"run {i}: drive force and rail pin force against time"))
    parts.append("</section>")
    return "\n".join(parts)


def check_detail(c, ch):
    """The detail cell of a consistency check."""
    if ch.part == "status":
        return "agree" if ch.passed else "DIFFER: see the status table"
    if ch.part == "attrs":
        return ("agree" if ch.passed else f"DIFFER: file says n_ok = {c.stats_attrs['n_ok']}, n_failed = "
                f"{c.stats_attrs['n_failed']}")
    cmp, key = ch.comparison, ch.source
    if ch.part == "counts":
        return num(f"check.{key}.count_mismatches", cmp.count_mismatches, tag="span") + " counts differ"
    if ch.part == "order":
        return ("largest difference / largest |value| "
                + num(f"check.{key}.order_max_diff", cmp.order, tag="span"))
    return ("largest difference / largest |value| " + num(f"check.{key}.moments_max_diff", cmp.moments, tag="span")
            + " (sums in another order round differently)")


def section_checks(c, checks, number):
    rows = [[esc(ch.what), ("<span class='okc'>pass</span>" if ch.passed
                            else "<span class='bad'>FAIL</span>"), check_detail(c, ch)]
            for ch in checks]
    return (f'<section id="checks"><h2>{number}. Consistency of the file</h2>'
            "<p>The report recomputes from <code>/runs</code> what the file also stores in "
            "<code>/stats</code>, and compares: counts exactly, other statistics to "
            f"{fmt(AGREE_RTOL)} of the largest |value| of the column.</p>"
            + table(["check", "result", "detail"], rows) + "</section>")
