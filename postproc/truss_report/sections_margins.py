"""truss_report.sections_margins: see the package docstring (postproc/truss_report/__init__.py)."""
from dataclasses import dataclass

import numpy as np

import run_figures as rf
from .constants import (AGREE_RTOL, MAX_HISTORY_FIGURES, OUTPUTS, TORNADO_TOP, TORQUE_RTOL,
                        output_label)
from .figures import fig_motor, fig_sobol, fig_tornado
from .design import readable_unit
from .page import esc, fmt, num, table
from .stats import clopper_pearson, spearman_table


def section_margins(page, c):
    head = '<section id="margins"><h2>4. Margins: drive torque against the motor stall torque</h2>'
    if c.attrs["drive_mode"] == "velocity":
        return section_margins_velocity(page, c, head)
    if c.attrs["drive_mode"] != "motor":
        return (head + f"<p>The drive mode is <b>{esc(c.attrs['drive_mode'])}</b>: the drive "
                "applies a prescribed torque, there is no motor to compare with.</p></section>")
    stall_code = [k for k, v in c.status_name.items() if v == "stall"]
    stalled = np.isin(c.status, stall_code)
    torque = c.outputs["peak_drive_torque_Nm"]
    u, f = c.display_units.get("torque", c.units["peak_drive_torque_Nm"], torque)
    stall_t, source = c.stall_torque, c.stall_torque_source
    ok_t = c.ok & np.isfinite(torque) & np.isfinite(stall_t)
    ok_exceed = ok_t & (torque > stall_t * (1.0 + TORQUE_RTOL))
    n_cons = int(ok_t.sum() + stalled.sum())
    k = int(ok_exceed.sum() + stalled.sum())
    if n_cons == 0:
        return head + "<p>No ok or stalled run: nothing to compare.</p></section>"
    p = k / n_cons
    lo, hi = clopper_pearson(k, n_cons)
    util = torque[ok_t] / stall_t[ok_t]
    nominal = float((c.base_scene.get("drive") or {}).get("stall_torque_Nm", float("nan")))
    fig = fig_motor(page.plt, torque / f, stall_t / f, ok_t, stalled, nominal / f, u)
    rows = [
        ["stall torque of the base scene", num("motor.stall_torque_nominal", nominal, u, factor=f)],
        ["runs considered (ok with a finite peak torque, + stalled)", num("motor.n_considered",
                                                                         n_cons)],
        ["stalled runs (status stall)", num("motor.n_stall", int(stalled.sum()))],
        ["ok runs with peak torque > stall torque", num("motor.n_ok_exceed", int(ok_exceed.sum()))],
        ["exceedances", num("motor.n_exceed", k)],
        ["probability of exceeding the stall torque", num("motor.p_exceed", p, digits=4)],
        ["95 % Clopper-Pearson interval, low", num("motor.p_exceed.ci_lo", lo, digits=4)],
        ["95 % Clopper-Pearson interval, high", num("motor.p_exceed.ci_hi", hi, digits=4)],
        ["largest peak torque / stall torque of an ok run",
         num("motor.utilisation_max", float(np.max(util)) if len(util) else float("nan"),
             digits=10)],
    ]
    excluded = int(np.sum(~c.ok & ~stalled))
    return (head + f"<p>Stall torque: {source}. A run exceeds the stall torque when it stalled "
            "(status <code>stall</code>: the motor could not drive the mast, so the torque the "
            "mast needed exceeded what the motor gives; <b>stalled runs count as exceedances</b>) "
            f"or when its peak torque is above its stall torque × (1 + {TORQUE_RTOL:g}). "
            "The motor gives its stall torque at zero speed, at the start, so in an ok run the "
            "peak torque equals the stall torque up to rounding. The probability is exceedances / "
            "runs considered, with an exact (Clopper-Pearson) 95 % interval; the "
            + num("motor.n_other_failures", excluded, tag="span")
            + " runs that failed for another reason are not counted.</p>"
            + page.figure(fig, "motor_torque_margin.png",
                          "stall torque of the ok and stalled runs, and peak drive torque against "
                          "stall torque")
            + table(["", "value"], rows, "narrow") + "</section>")


def section_margins_velocity(page, c, head):
    torque = c.outputs["peak_drive_torque_Nm"]
    u, f = c.display_units.get("torque", c.units["peak_drive_torque_Nm"], torque)
    if c.motor_torque_at_speed is None:
        return (head + "<p>This file has no <code>/runs/motor_torque_at_speed_Nm</code> (it was "
                "written before the simulator stored the motor's torque at the prescribed speed): "
                "the available torque is not in the file, so this margin is not computed.</p></section>")
    avail = c.motor_torque_at_speed  # the simulator's motor law, never written again here
    considered = c.ok & np.isfinite(torque) & np.isfinite(avail)
    n_cons = int(considered.sum())
    if n_cons == 0:
        return head + "<p>No ok run with a finite peak torque: nothing to compare.</p></section>"
    exceed = considered & (torque > avail)
    k = int(exceed.sum())
    lo, hi = clopper_pearson(k, n_cons)
    drive = c.base_scene.get("drive") or {}
    omega = 2.0 * np.pi * float(drive["speed_m_per_s"]) / float(drive["screw_lead_m"])
    ratio = avail[considered] / torque[considered]
    fig, ax = page.plt.subplots(figsize=(10.0, 4.2))
    ax.hist(torque[considered] / f, bins=60, color="C0", label=f"peak drive torque, {n_cons} ok runs")
    a_min, a_max = float(np.min(avail[considered])), float(np.max(avail[considered]))
    ax.axvline(a_min / f, color="C3", ls="--", lw=1.2,
               label=f"available at the prescribed speed: {fmt(a_min / f, 4)} {u}"
               + (f" (smallest; largest {fmt(a_max / f, 4)} {u})" if a_max > a_min else ""))
    ax.set_xlabel(f"drive torque, the three screws together ({u})")
    ax.set_ylabel("runs")
    ax.legend(loc="upper left", bbox_to_anchor=(0.0, -0.18), ncol=2, frameon=False)
    ax.grid(True, alpha=0.3)
    fig.set_layout_engine("tight")   # applied when drawn
    rows = [
        ["motor stall torque of the scene", num("velmargin.stall_torque", float(drive["stall_torque_Nm"]), u, factor=f)],
        ["motor no-load speed of the scene", num("velmargin.no_load_speed", float(drive["no_load_speed_rad_per_s"]), "rad/s")],
        ["screw speed the prescribed drive speed needs", num("velmargin.required_speed", omega, "rad/s")],
        ["runs considered (ok, finite peak torque)", num("velmargin.n_considered", n_cons)],
        ["runs whose peak torque exceeds the available torque", num("velmargin.n_exceed", k)],
        ["probability of exceeding", num("velmargin.p_exceed", k / n_cons, digits=4)],
        ["95 % Clopper-Pearson interval, low", num("velmargin.p_exceed.ci_lo", lo, digits=4)],
        ["95 % Clopper-Pearson interval, high", num("velmargin.p_exceed.ci_hi", hi, digits=4)],
        ["smallest available / peak torque", num("velmargin.ratio_min", float(np.min(ratio)), digits=6)],
        ["median available / peak torque", num("velmargin.ratio_p50", float(np.percentile(ratio, 50)), digits=6)],
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


@dataclass
class InputColumn:
    label: str
    values: np.ndarray
    aggregate: bool       # the per-dispersion aggregate (or a per-run dispersion itself)
    units: str = "1"      # of the values; an aggregate (per-bay/frame mean) is a relative deviation
    relative: bool = False  # values are (value - nominal) / nominal


def input_columns(c):
    """Every sampled input column and one aggregate per dispersion (see aggregate_input)."""
    cols = []
    for d in c.dispersions:
        if d.per == "run":
            cols.append(InputColumn(d.key, d.values, True, d.units))
            continue
        start = 1 if d.per == "bay" else 0
        for j in range(d.values.shape[1]):
            cols.append(InputColumn(f"{d.key}[{d.per} {j + start}]", d.values[:, j], False,
                                    d.units))
        cols.append(InputColumn(aggregate_label(d), aggregate_input(d), True,
                                "1" if d.nominal != 0 else d.units, d.nominal != 0))
    return cols


def input_axis(col):
    """(axis label, values) of an input column for a plot: a relative deviation in %, a length
    in mm, a mass in g (when the values are that small), else the file's unit."""
    if col.relative:
        key, per = col.label[:-1].split(" (mean over ")
        return f"{key}: mean relative\ndeviation over {per} (%)", 100.0 * col.values
    finite = col.values[np.isfinite(col.values)]
    lab, f = readable_unit(col.units, float(np.max(np.abs(finite))) if len(finite) else np.nan)
    return (col.label + (f" ({lab})" if lab != "1" else ""), col.values / f)


def aggregate_label(d):
    return f"{d.key} (mean over {d.per}s)"


def aggregate_input(d):
    """Per run: the mean over the run's bays (frames) of (value - nominal) / nominal
    ((value - nominal) when the nominal is 0)."""
    dev = d.values - d.nominal
    if d.nominal != 0:
        dev = dev / d.nominal
    finite = np.isfinite(dev)
    count = finite.sum(axis=1)
    total = np.where(finite, dev, 0.0).sum(axis=1)
    return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def rank_correlations(c):
    """{output: {input label: (Spearman rho, pairs)}} over the ok runs, computed once per report
    (the tornado charts and the scatter plots of the top inputs read the same table)."""
    if getattr(c, "rank_correlations", None) is None:
        cols = input_columns(c)
        c.rank_correlations, ranks = {}, {}
        for key in OUTPUTS:
            y = np.where(c.ok, c.outputs[key], np.nan)
            c.rank_correlations[key] = dict(zip((col.label for col in cols),
                                                spearman_table([col.values for col in cols], y,
                                                               ranks)))
    return c.rank_correlations


def section_sensitivity(page, c):
    out = ['<section id="sensitivity"><h2>5. What drives the loads</h2>']
    if not c.dispersions:
        return out[0] + "<p>No dispersed input.</p></section>"
    cols = input_columns(c)
    rho = rank_correlations(c)
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
    rows = [[f"<code>{esc(lab)}</code>"] + [num(f"spearman.{k}.{lab}", rho[k][lab][0], digits=3)
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
        ranked = sorted(((lab, r, n) for lab, (r, n) in rho[key].items() if np.isfinite(r)),
                        key=lambda t: -abs(t[1]))[:TORNADO_TOP]
        if not ranked:
            figs.append(f"<div class='cell'><p class='note'><code>{key}</code>: no input "
                        "correlation defined (no finite ok value, or a constant output).</p></div>")
            continue
        n_y = int(np.sum(c.ok & np.isfinite(c.outputs[key])))
        fig = fig_tornado(page.plt, ranked, aggregate, f"{output_label(key, c.attrs['direction'])} (n = {n_y})",
                          1.96 / np.sqrt(max(n_y - 1, 1)))
        detail = table(["input", "ρ", "runs"],
                       [[f"<code>{esc(lab)}</code>", num(f"spearman.{key}.{lab}", r, digits=3),
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


def proportional_to(c):
    """{output: earlier output} for outputs whose ok values are a constant multiple of an earlier
    one's (drive torque = force x lead / 2 pi): one tornado serves both."""
    res = {}
    keys = list(OUTPUTS)
    for i, k in enumerate(keys):
        for j in keys[:i]:
            a, b = c.outputs[j][c.ok], c.outputs[k][c.ok]
            m = np.isfinite(a) & np.isfinite(b) & (a != 0)
            if m.sum() >= 3 and j not in res:
                r = b[m] / a[m]
                if np.ptp(r) <= 1e-9 * abs(np.mean(r)):
                    res[k] = j
                    break
    return res


def subsection_sobol(page, c):
    s = c.sensitivity
    factors = s["factor"]
    outs = s["outputs"]
    meth = outs[next(iter(outs))]
    parts = ["<h3>Sobol' indices (Saltelli sampling)</h3>",
             "<p>From <code>/sensitivity</code>, as the campaign computed them: method "
             f"“{esc(meth['method'])}”, {fmt(meth['confidence'], 3)} confidence intervals from "
             f"{meth['n_resamples']} bootstrap resamples. A factor is a whole dispersion "
             "(a per-bay "
             "dispersion moves all its bays together). Indices are dimensionless.</p>",
             out_of_range_note(outs),
             design_correlation_note(c, len(factors)),
             page.figure(fig_sobol(page.plt, factors, outs), "sobol_indices.png",
                         "first-order and total Sobol' indices with their confidence intervals")]
    cells = []
    for key, o in outs.items():
        rows = [[f"<code>{esc(fac)}</code>"]
                + [num(f"sobol.{key}.{fac}.{k}", float(o[k][g]), digits=3)
                   for k in ("first_order", "first_order_lo", "first_order_hi",
                             "total", "total_lo", "total_hi")] for g, fac in enumerate(factors)]
        cells.append(f"<div class='cell'><h4><code>{key}</code></h4><p>blocks used "
                     f"{num(f'sobol.{key}.n_blocks', o['n_blocks'], tag='span')}, dropped "
                     f"{num(f'sobol.{key}.n_blocks_dropped', o['n_blocks_dropped'], tag='span')}"
                     "</p>" + table(["factor", "S1", "S1 low", "S1 high", "ST", "ST low",
                                     "ST high"], rows, "narrow") + "</div>")
    parts.append("<div class='grid'>" + "".join(cells) + "</div>")
    return "\n".join(parts)


def calc_design_correlations(c, n_factors):
    """Largest |rank correlation| between the A and B rows of each dispersion's columns (one per
    bay or frame for per-bay/per-frame keys). Saltelli's design (block of G + 2 runs: A, B, AB_1
    .. AB_G) assumes A and B independent; a correlated pair biases that factor's indices. Campaign
    files of schema_version 1 drew A and B from one Sobol' point, some of whose pairs of dimensions
    correlate strongly at small N (docs/campaigns.md). Returns {key: (rho, N)}."""
    block = n_factors + 2
    n_blocks = len(c.status) // block
    res = {}
    if n_blocks < 3:
        return res, n_blocks
    for d in c.dispersions:
        v = np.asarray(d.values, dtype=float)
        v = v[: n_blocks * block].reshape(n_blocks * block, -1)
        worst = 0.0
        for j in range(v.shape[1]):
            a, b = v[0::block, j], v[1::block, j]
            if np.ptp(a) == 0 or np.ptp(b) == 0:
                continue
            ra, rb = np.argsort(np.argsort(a)), np.argsort(np.argsort(b))
            r = float(np.corrcoef(ra, rb)[0, 1])
            if abs(r) > abs(worst):
                worst = r
        res[d.key] = worst
    return res, n_blocks


def design_correlation_note(c, n_factors):
    """A warning naming the factors whose A and B columns correlate by more than 4 / sqrt(N)
    (four standard deviations of the correlation of N independent pairs)."""
    rho, n_blocks = calc_design_correlations(c, n_factors)
    if not rho:
        return ""
    limit = 4.0 / np.sqrt(n_blocks)
    bad = {k: r for k, r in rho.items() if abs(r) > limit}
    if not bad:
        return ""
    return ("<p class='warn'>Design check: the A and B samples of "
            + ", ".join(f"<code>{esc(k)}</code> (rank correlation {r:.2f})" for k, r in sorted(bad.items()))
            + f" are correlated beyond 4/&radic;N = {limit:.2f} (N = {n_blocks} blocks). Saltelli's "
              "estimators assume them independent: these factors' indices may be biased at this N "
              "(files of schema_version 1 drew A and B from one Sobol' point, whose high dimensions "
              "do this; docs/campaigns.md). Run more blocks before relying on them.</p>")


def out_of_range_note(outs):
    """A warning when point estimates fall outside [0, 1]: the estimators are unbiased, not
    bounded, and such values mean too few blocks for that output."""
    bad = [key for key, o in outs.items()
           if np.any((o["first_order"] < 0) | (o["first_order"] > 1)
                     | (o["total"] < 0) | (o["total"] > 1))]
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
        parts.append(page.figure(rf.fig5(page.plt, c.histories[i]), f"history_run_{i}.png",
                                 f"run {i}: drive force and rail pin force against time"))
    parts.append("</section>")
    return "\n".join(parts)


def section_checks(page, number):
    rows = [[esc(what), ("<span class='okc'>pass</span>" if passed
                         else "<span class='bad'>FAIL</span>"), detail]
            for what, passed, detail in page.checks]
    return (f'<section id="checks"><h2>{number}. Consistency of the file</h2>'
            "<p>The report recomputes from <code>/runs</code> what the file also stores in "
            "<code>/stats</code>, and compares: counts exactly, other statistics to "
            f"{AGREE_RTOL:g} of the largest |value| of the column.</p>"
            + table(["check", "result", "detail"], rows) + "</section>")
