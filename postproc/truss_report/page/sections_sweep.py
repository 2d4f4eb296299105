"""truss_report.page.sections_sweep: the report of a design sweep ([sweep] of a campaign, the file's
/sweep, docs/hdf5-schema.md): the failure probability at each design value with its interval, on
a log axis, the target, and the allowable (the extreme design value whose one-sided upper
confidence bound on p stays at or below the target) with its interval; the verdict compares the
allowable with the design's own value: PASS on its safe side, FAIL on its unsafe side, NOT
ASSESSED when the swept range holds no allowable or the file's numbers do not support its verdict
(judging.sweep: exit codes as every report: 0, 3, 4). Each value's runs are the runs of one
standalone campaign (its seed in /sweep/master_seed), or one set of importance-sampling runs serves
every value by reweighting; either way the runs are not draws of the design's population: no design
loads.

The table is truss_report.read_sweep's DataFrame: one row per design value, the sweep's settings
and the allowable in df.attrs."""
from functools import partial

import math

import numpy as np

from ..judging.sweep import NO_RESULT_SHARE, flat_values, judge_sweep, sweep_reason
from ..judging.motor_answer import SIZING_VARIABLE, SWEEP
from ..judging.verdict import EXIT_STATUS, NOT_ASSESSED, PASS, VERDICT_WORDS
from .exports import SWEEP_CSV, VERDICT_JSON, sweep_csv, verdict_json
from .html import esc, html_page, num, table
from .motor_answer import motor_answer_html, motor_answer_lines
from .numbers import DASH, P_LEAST, fmt, fmt_at, fmt_p, message_text, p_digits, readable_unit, resolution, unit_text
from .render import Report
from .sections_subset import plateau_warning
from .top import campaign_doc, model_limits_html, signoff_html


def design_unit(s):
    """(label, factor) of the design variable: one prefix for the whole sweep (page.numbers)."""
    return readable_unit(s.attrs["design_units"], float(np.nanmax(np.abs(s["value"].to_numpy(dtype=float)))))


def allowable_at(s):
    """The resolution of the allowable, its estimate and interval (display unit): two digits of the
    interval's half width (of the allowable's distance to its estimate when the interval is open)."""
    a = s.attrs["allowable"]
    f = design_unit(s)[1]
    half = (a["upper"] - a["lower"]) / 2.0 if math.isfinite(a["upper"] - a["lower"]) else abs(a["value"] - a["estimate"])
    return resolution([a["value"] / f], half / f)


def design_text(s, v):
    """A design value in the sweep's unit: declared values as given, the allowable's to its resolution."""
    unit, f = design_unit(s)
    return f"{fmt(v / f)} {unit}" if math.isfinite(v) else DASH


def allowable_sentence(s):
    """'drive.stall_torque_Nm ≥ 14.08 mN m (95 % upper bound on P(...) ≤ 1e-06)', or why none."""
    a, at = s.attrs["allowable"], s.attrs
    unit, f = design_unit(s)
    if a["status"] != "found":
        return f"no allowable in the swept range: {message_text(a['message'])}"
    if not math.isfinite(a["value"]):
        return "no allowable: the file's allowable is not a number"
    rel = "≥" if a["safe_side"] == "above" else "≤"
    return (f"{at['variable']} {rel} {fmt_at(a['value'] / f, allowable_at(s))} {unit} ({fmt(100 * at['confidence'])} % "
            f"upper bound on P({failure_text(s, html=False)}) ≤ {fmt(at['target_probability'])})")


def failure_text(s, html=True):
    """The failure event, its threshold in the design variable's unit when the two share one (a
    torque margin of a stall-torque sweep: one prefix per quantity)."""
    at = s.attrs
    col = f"<code>{esc(at['failure_column'])}</code>" if html else at["failure_column"]
    units = at.get("failure_units", "")
    unit, f = ("" if units == "1" else unit_text(units)), 1.0   # a ratio's margin: no unit after it
    if units == at["design_units"]:
        unit, f = design_unit(s)
    if at["failure_kind"] == "margin":
        return f"{col} ≤ 0 {unit}".strip()
    return f"{col} {'≥' if at['failure_kind'] == 'above' else '≤'} {fmt(at['failure_threshold'] / f)} {unit}".strip()


def reason_text(s, what, rows):
    """Why the report does not show the file's verdict, in words (judging.sweep.SweepJudgement)."""
    a, values = s.attrs["allowable"], ", ".join(design_text(s, float(s["value"].iloc[k])) for k in rows)
    return {"not_found": f"the file's verdict {a['verdict']} has no allowable (status {a['status']})",
            "no_estimate": "no design value has an estimate of p",
            "allowable_nan": f"the file's allowable is not a number (status {a['status']}, verdict {a['verdict']})",
            "own_nan": "the design's own value is not a number",
            "wrong_side": (f"the file's verdict {a['verdict']} names the other side of the allowable than the "
                           f"design's own value {design_text(s, a['own_value'])} lies on"),
            "safe_side_above_target": (f"at {values}, on the allowable's safe side, the upper bound on p exceeds "
                                       "the target"),
            "no_result": (f"at {values}, more than {fmt(100 * NO_RESULT_SHARE)} % of the runs gave no result (capped, "
                          "failed to solve, or no margin): they would count as safe"),
            "plateau": (f"the estimates at {values} may be biased low (a plateau of the margin), so the allowable may "
                        "lie on the unsafe side")}[what]


def verdict_lines(c, s):
    """The verdict and the sweep's headline for the terminal and the top of the page."""
    a, at = s.attrs["allowable"], s.attrs
    j = judge_sweep(s)
    name = c.attrs["campaign_name"]
    if j.reasons:
        head = (f"VERDICT: {VERDICT_WORDS[j.verdict]} — "
                + "; ".join(reason_text(s, what, rows) for what, rows in j.reasons) + f" ({name}, sweep)")
    elif j.verdict == NOT_ASSESSED:
        head = f"VERDICT: {VERDICT_WORDS[j.verdict]} — {message_text(sweep_reason(s))} ({name}, sweep)"
    else:
        side = "on the safe side of" if j.verdict == PASS else "on the unsafe side of"
        head = (f"VERDICT: {VERDICT_WORDS[j.verdict]} — the design's {design_text(s, a['own_value'])} is {side} the "
                f"allowable ({name}, sweep)")
    lines = [head, f"  allowable: {allowable_sentence(s)}"]
    if a["status"] == "found":
        unit, f = design_unit(s)
        e = allowable_at(s)
        lines.append(f"  estimate (p = target): {fmt_at(a['estimate'] / f, e)}"
                     f"{' ' + unit if math.isfinite(a['estimate']) else ''}; {fmt(100 * at['confidence'])} % interval "
                     f"of the crossing [{fmt_at(a['lower'] / f, e)}, {fmt_at(a['upper'] / f, e)}] {unit} (—: beyond "
                     "the swept range)")
    refined = int(s["refinement"].sum())
    # An importance sweep's values share one set of runs (reweighted to each value's law).
    shared = at["inner_method"] == "importance"
    how = "one set of importance-sampling runs reweighted to each" if shared else f"{at['inner_method']} at each"
    lines.append(f"  {len(s)} values of {at['variable']}"
                 f"{f' ({refined} placed by the refinement)' if refined else ''}, {how}, "
                 f"{int(s['runs'].iloc[0] if shared else s['runs'].sum())} runs")
    flat = flat_values(s)
    if flat:
        lines.append(f"  warning: at {design_text(s, float(s['value'].iloc[flat[0]]))} "
                     f"{plateau_warning(int(s['plateau_levels'].iloc[flat[0]]))}")
    return lines, j.verdict


def fig_sweep(plt, s):
    a, at = s.attrs["allowable"], s.attrs
    unit, factor = design_unit(s)
    x = s["value"].to_numpy() / factor
    fig, ax = plt.subplots(figsize=(8.0, 4.6))
    ok = s["p"].to_numpy() > 0
    lo = np.where(s["lower"] > 0, s["lower"], np.nan)
    ax.fill_between(x, lo, s["upper"], color="C0", alpha=0.2,
                    label=f"{fmt(100 * at['confidence'])} % interval of p")
    ax.plot(x[ok], s["p"][ok], "o-", color="C0", label="estimate p")
    fine = ok & s["refinement"].to_numpy()
    if fine.any():
        ax.plot(x[fine], s["p"][fine], "s", color="C0", mfc="white", label="estimate p, refinement values")
    ax.plot(x, s["upper_bound"], "v--", color="C1", label=f"one-sided {fmt(100 * at['confidence'])} % upper bound")
    ax.axhline(at["target_probability"], color="C3", lw=1.2, label=f"target {fmt(at['target_probability'])}")
    if a["status"] == "found" and math.isfinite(a["value"]):
        ax.axvline(a["value"] / factor, color="k", lw=1.2,
                   label=f"allowable {fmt_at(a['value'] / factor, allowable_at(s))} {unit}")
        if math.isfinite(a["lower"]) and math.isfinite(a["upper"]):
            ax.axvspan(a["lower"] / factor, a["upper"] / factor, color="k", alpha=0.08,
                       label="interval of the crossing")
    if math.isfinite(a["own_value"]) and x.min() <= a["own_value"] / factor <= x.max():
        ax.axvline(a["own_value"] / factor, color="C2", lw=1.2, ls=":", label="the design's own value")
    ax.set_yscale("log")
    ax.set_xlabel(f"{at['variable']} ({unit})")
    ax.set_ylabel("failure probability")
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig


def sweep_row(s, k, r, unit, f):
    """One design value's cells: p shown to its interval (as its upper bound when no run failed),
    its CoV ("—" when p = 0: undefined), the runs without a result."""
    d = p_digits(r.p, r.lower, r.upper)
    prob = [num(f"sweep.{col}{k}", float(getattr(r, col)), digits=d) for col in ("lower", "upper", "upper_bound")]
    return [num(f"sweep.value{k}", float(r.value), unit, factor=f),
            num(f"sweep.p{k}", float(r.p), text=fmt_p(r.p, r.lower, r.upper, r.upper_bound)),
            num(f"sweep.cov{k}", float(r.cov), digits=P_LEAST) if r.p > 0 else f"<td>{DASH}</td>",
            *prob, num(f"sweep.runs{k}", int(r.runs)),
            num(f"sweep.no_result{k}", int(r.no_result)) if r.no_result >= 0 else f"<td>{DASH}</td>",
            esc(r.status), num(f"sweep.plateau{k}", int(r.plateau_levels)),
            "refinement" if r.refinement else "listed"]


def sweep_columns(s):
    """The indices of sweep_row's cells the table shows: the plateau levels only for subset
    simulation (no other method has levels that can stall), where each value was placed only when
    the sweep refined its bracket."""
    drop = set()
    if s.attrs["inner_method"] != "subset":
        drop.add(9)
    if not s["refinement"].any():
        drop.add(10)
    return [i for i in range(11) if i not in drop]


def section_sweep(page, s):
    at = s.attrs
    unit, f = design_unit(s)
    conf = fmt(100 * at["confidence"])
    shown = sweep_columns(s)
    rows = [[row[i] for i in shown] for row in (sweep_row(s, k, r, unit, f) for k, r in enumerate(s.itertuples()))]
    flat = flat_values(s)
    warn = ""
    if flat:
        warn = (f"<p class='warn'>Biased low? At {', '.join(design_text(s, float(s['value'].iloc[k])) for k in flat)}, "
                f"{esc(plateau_warning(int(s['plateau_levels'].iloc[flat[0]])))}.</p>")
    return ("<section id='sweep'><h2>Failure probability against the design variable</h2>"
            f"<p>Failure event: {failure_text(s)}. {runs_text(at)} The band is each estimate's two-sided {conf} % interval, "
            f"the dashed line its one-sided {conf} % upper bound, which the allowable keeps at or below "
            f"the target {fmt(at['target_probability'])}; probabilities are shown within [0, 1], an estimate "
            "of 0 as its upper bound. Runs without a result (capped, failed to solve, or without a margin) "
            f"count as safe in an estimate: past {fmt(100 * NO_RESULT_SHARE)} % of a value's runs its estimate "
            "does not support a PASS.</p>"
            + page.figure(partial(fig_sweep, page.plt, s), "sweep.png",
                          "failure probability against the design value (log axis), target and allowable")
            + refine_html(at) + warn
            + table([h for i, h in enumerate(["value", "p", "CoV", f"{conf} % low", f"{conf} % high",
                                              f"{conf} % upper bound", "runs", "runs without a result", "status",
                                              "plateau levels", "placed"]) if i in shown], rows, "narrow")
            + "</section>")


def runs_text(at):
    """Where each value's estimate comes from: runs of its own, or one set of runs reweighted."""
    if at["inner_method"] == "importance":
        return ("One set of cross-entropy importance-sampling runs serves every value of <code>"
                + esc(at["variable"]) + "</code>, reweighted to each value's law (refused where the weights "
                "degenerate).")
    return (f"At each value of <code>{esc(at['variable'])}</code> the campaign ran as a campaign of its own "
            f"({esc(at['inner_method'])}; its seed in <code>/sweep/master_seed</code>).")


def refine_html(at):
    """What the refinement did (sweep.refine values inside the bracket of the listed values'
    allowable, docs/campaigns.md), or nothing when the campaign asked for none."""
    if int(at.get("refine", 0)) == 0:
        return ""
    return (f"<p>Refinement (<code>sweep.refine = {int(at['refine'])}</code>): "
            f"{esc(message_text(at['refine_message']))}. The allowable is read from all values, listed and placed.</p>")


def section_allowable(s):
    a = s.attrs["allowable"]
    unit, f = design_unit(s)
    e = allowable_at(s)
    rows = [["allowable (upper bound = target)", num("sweep.allowable", a["value"], unit, factor=f, at=e)],
            ["estimate (p = target)", num("sweep.allowable.estimate", a["estimate"], unit, factor=f, at=e)],
            ["interval of the crossing, low", num("sweep.allowable.lower", a["lower"], unit, factor=f, at=e)],
            ["interval of the crossing, high", num("sweep.allowable.upper", a["upper"], unit, factor=f, at=e)],
            ["the design's own value", num("sweep.own_value", a["own_value"], unit, factor=f)]]
    return ("<section id='allowable'><h2>Allowable</h2>"
            f"<p>{esc(allowable_sentence(s))}. Status <b>{esc(a['status'])}</b>: {esc(message_text(a['message']))}. "
            f"How: {esc(a['method'])}. An interval end outside the swept values is shown as —.</p>"
            + table(["quantity", "value"], rows, "narrow") + "</section>")


def verdict_items(s, v):
    """(item, status, reason) of the verdict for verdict.json: each reason the report has for not
    showing the file's verdict, else the file's own reason."""
    j = judge_sweep(s)
    if j.reasons:
        return [(what, v, reason_text(s, what, rows)) for what, rows in j.reasons]
    return [("allowable", v, message_text(sweep_reason(s)))]


def sweep_report(page, c, s, revision, nominal_html, answer=None):
    """The report of a design sweep (s: its table, judging.sweep.sweep_frame; answer: the motor
    answer with a load report of the same mast, judging.motor_answer, or None), with its lines for
    the terminal and its verdict."""
    lines, v = verdict_lines(c, s)
    unit, f = design_unit(s)
    summary = lines + motor_answer_lines(answer, unit, f, allowable_at(s))
    page.text_file(SWEEP_CSV, sweep_csv(s))
    page.text_file(VERDICT_JSON, verdict_json(v, EXIT_STATUS[v], "sweep", c, verdict_items(s, v), answer))
    verdict = (f"<div class='verdict {v}' data-key='verdict' data-value='{v}' "
               f"data-reason='{esc(sweep_reason(s))}'>"
               + "<br>".join(esc(x) for x in lines) + "</div>")
    motor = (motor_answer_html(answer, SWEEP, unit, f, allowable_at(s))
             if answer is not None or s.attrs["variable"] == SIZING_VARIABLE else "")
    toc = ("<nav><a href='#sweep'>Probability against the design variable</a> · "
           + ("<a href='#motor-answer'>One motor answer</a> · " if motor else "")
           + "<a href='#allowable'>Allowable</a> · "
           "<a href='#nominal'>Nominal run</a> · <a href='#limits'>Model limits</a> · "
           "<a href='#signoff'>Sign-off</a></nav>")
    # The plot on page 1 with its verdict; the motor answer after it.
    body = [verdict, section_sweep(page, s), motor, section_allowable(s), nominal_html]
    title = f"Design-sweep report: campaign “{c.attrs['campaign_name']}”"
    doc = campaign_doc(c, f"<b>{VERDICT_WORDS[v]}</b>: {esc(allowable_sentence(s))}")
    return Report(html_page(title, c.path, c.sha256, toc + "\n".join(body) + model_limits_html()
                            + signoff_html(revision, c.path, c.sha256), doc), summary, v)
