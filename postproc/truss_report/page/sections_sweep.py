"""truss_report.page.sections_sweep: the report of a design sweep ([sweep] of a campaign, the file's
/sweep, docs/hdf5-schema.md): the failure probability at each design value with its interval, on
a log axis, the target, and the allowable (the extreme design value whose one-sided upper
confidence bound on p stays at or below the target) with its interval; the verdict compares the
allowable with the design's own value: PASS on its safe side, FAIL on its unsafe side, NOT
ASSESSED when the swept range holds no allowable (exit codes as every report: 0, 3, 4). Each
value's runs are the runs of one standalone campaign (its seed in /sweep/master_seed), so the runs
as a whole are not draws of one population: no design loads.

The table is truss_report.read_sweep's DataFrame: one row per design value, the sweep's settings
and the allowable in df.attrs."""
import math

import numpy as np

from ..judging.sweep import flat_values, sweep_reason, sweep_verdict
from ..judging.verdict import NOT_ASSESSED, PASS, VERDICT_WORDS
from .html import esc, fmt, html_page, num, table, unit_text
from .render import Report
from .sections_subset import plateau_warning
from .top import campaign_doc, model_limits_html, signoff_html


def _design_unit(units):
    """Display unit and factor of the design variable: N m shown in mN m, m in mm."""
    if units in ("Nm", "N m"):
        return "mN m", 1e-3
    if units == "m":
        return "mm", 1e-3
    return units, 1.0


def allowable_sentence(s):
    """'drive.stall_torque_Nm >= 4.8848 mN m (95 % upper bound on P(...) <= 1e-06)', or why none."""
    a, at = s.attrs["allowable"], s.attrs
    unit, factor = _design_unit(at["design_units"])
    event = failure_text(at, html=False)
    if a["status"] != "found":
        return f"no allowable in the swept range: {a['message']}"
    rel = "≥" if a["safe_side"] == "above" else "≤"
    return (f"{at['variable']} {rel} {fmt(a['value'] / factor, 5)} {unit} ({fmt(100 * at['confidence'])} % upper bound "
            f"on P({event}) ≤ {fmt(at['target_probability'])})")


def failure_text(at, html=True):
    col = f"<code>{esc(at['failure_column'])}</code>" if html else at["failure_column"]
    unit = unit_text(at.get("failure_units", ""))
    if at["failure_kind"] == "margin":
        return f"{col} ≤ 0 {unit}".strip()
    return f"{col} {'≥' if at['failure_kind'] == 'above' else '≤'} {fmt(at['failure_threshold'])} {unit}".strip()


def verdict_lines(c, s):
    """The verdict and the sweep's headline for the terminal and the top of the page."""
    a, at = s.attrs["allowable"], s.attrs
    unit, factor = _design_unit(at["design_units"])
    own = f"{fmt(a['own_value'] / factor, 5)} {unit}"
    verdict = sweep_verdict(s)
    flat = flat_values(s)
    if verdict == NOT_ASSESSED:
        head = f"VERDICT: {VERDICT_WORDS[verdict]} — {sweep_reason(s)} ({c.attrs['campaign_name']}, sweep)"
    else:
        side = "on the safe side of" if verdict == PASS else "on the unsafe side of"
        head = (f"VERDICT: {VERDICT_WORDS[verdict]} — the design's {own} is {side} the allowable "
                f"({c.attrs['campaign_name']}, sweep)")
    lines = [head, f"  allowable: {allowable_sentence(s)}"]
    if a["status"] == "found":
        lo, hi = a["lower"], a["upper"]
        est = a["estimate"]
        lines.append(f"  estimate (p = target): {fmt(est / factor, 5)}{' ' + unit if math.isfinite(est) else ''}; "
                     f"{fmt(100 * at['confidence'])} % interval of the crossing "
                     f"[{fmt(lo / factor, 5)}, {fmt(hi / factor, 5)}] {unit} (—: beyond the swept range)")
    refined = int(s["refinement"].sum())
    lines.append(f"  {len(s)} values of {at['variable']}"
                 f"{f' ({refined} placed by the refinement)' if refined else ''}, {at['inner_method']} at each, "
                 f"{int(s['runs'].sum())} runs")
    if flat:
        lines.append(f"  warning: at {fmt(float(s['value'].iloc[flat[0]]) / factor, 4)} {unit} "
                     f"{plateau_warning(int(s['plateau_levels'].iloc[flat[0]]))}")
    return lines


def fig_sweep(plt, s):
    a, at = s.attrs["allowable"], s.attrs
    unit, factor = _design_unit(at["design_units"])
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
    if a["status"] == "found":
        ax.axvline(a["value"] / factor, color="k", lw=1.2, label=f"allowable {fmt(a['value'] / factor, 4)} {unit}")
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


def section_sweep(page, s):
    at = s.attrs
    unit, factor = _design_unit(at["design_units"])
    conf = fmt(100 * at["confidence"])
    rows = [[num(f"sweep.value{k}", float(r.value), unit, factor=factor), num(f"sweep.p{k}", float(r.p), digits=4),
             num(f"sweep.cov{k}", float(r.cov), digits=3), num(f"sweep.lower{k}", float(r.lower), digits=3),
             num(f"sweep.upper{k}", float(r.upper), digits=3),
             num(f"sweep.upper_bound{k}", float(r.upper_bound), digits=3), num(f"sweep.runs{k}", int(r.runs)),
             esc(r.status), num(f"sweep.plateau{k}", int(r.plateau_levels)),
             "refinement" if r.refinement else "listed"] for k, r in enumerate(s.itertuples())]
    flat = flat_values(s)
    warn = ""
    if flat:
        at_values = ", ".join(fmt(float(s["value"].iloc[k]) / factor, 4) for k in flat)
        warn = (f"<p class='warn'>Biased low? At {at_values} {esc(unit)}, "
                f"{esc(plateau_warning(int(s['plateau_levels'].iloc[flat[0]])))}.</p>")
    return ("<section id='sweep'><h2>Failure probability against the design variable</h2>"
            f"<p>Failure event: {failure_text(at)}. At each value of <code>{esc(at['variable'])}</code> "
            f"the campaign ran as a campaign of its own ({esc(at['inner_method'])}; its seed in "
            f"<code>/sweep/master_seed</code>). The band is each estimate's two-sided {conf} % interval, "
            f"the dashed line its one-sided {conf} % upper bound, which the allowable keeps at or below "
            f"the target {fmt(at['target_probability'])}.</p>"
            + page.figure(fig_sweep(page.plt, s), "sweep.png",
                          "failure probability against the design value (log axis), target and allowable")
            + refine_html(at) + warn
            + table(["value", "p", "CoV", f"{conf} % low", f"{conf} % high", f"{conf} % upper bound", "runs",
                     "status", "plateau levels", "placed"], rows, "narrow") + "</section>")


def refine_html(at):
    """What the refinement did (sweep.refine values inside the bracket of the listed values'
    allowable, docs/campaigns.md), or nothing when the campaign asked for none."""
    if int(at.get("refine", 0)) == 0:
        return ""
    return (f"<p>Refinement (<code>sweep.refine = {int(at['refine'])}</code>): "
            f"{esc(at['refine_message'])}. The allowable is read from all values, listed and placed.</p>")


def section_allowable(s):
    a, at = s.attrs["allowable"], s.attrs
    unit, factor = _design_unit(at["design_units"])
    rows = [["allowable (upper bound = target)", num("sweep.allowable", a["value"], unit, factor=factor)],
            ["estimate (p = target)", num("sweep.allowable.estimate", a["estimate"], unit, factor=factor)],
            ["interval of the crossing, low", num("sweep.allowable.lower", a["lower"], unit, factor=factor)],
            ["interval of the crossing, high", num("sweep.allowable.upper", a["upper"], unit, factor=factor)],
            ["the design's own value", num("sweep.own_value", a["own_value"], unit, factor=factor)]]
    return ("<section id='allowable'><h2>Allowable</h2>"
            f"<p>{esc(allowable_sentence(s))}. Status <b>{esc(a['status'])}</b>: {esc(a['message'])}. "
            f"How: {esc(a['method'])}. An interval end outside the swept values is shown as —.</p>"
            + table(["quantity", "value"], rows, "narrow") + "</section>")


def sweep_report(page, c, s, revision, nominal_html):
    """The report of a design sweep (s: its table, judging.sweep.sweep_frame), with its lines for
    the terminal and its verdict."""
    summary = verdict_lines(c, s)
    v = sweep_verdict(s)
    verdict = (f"<div class='verdict {v}' data-key='verdict' data-value='{v}' "
               f"data-reason='{esc(sweep_reason(s))}'>"
               + "<br>".join(esc(x) for x in summary) + "</div>")
    toc = ("<nav><a href='#sweep'>Probability against the design variable</a> · <a href='#allowable'>Allowable</a> · "
           "<a href='#nominal'>Nominal run</a> · <a href='#limits'>Model limits</a> · "
           "<a href='#signoff'>Sign-off</a></nav>")
    body = [verdict, section_sweep(page, s), section_allowable(s), nominal_html]
    title = f"Design-sweep report: campaign “{c.attrs['campaign_name']}”"
    doc = campaign_doc(c, f"<b>{VERDICT_WORDS[v]}</b>: {esc(allowable_sentence(s))}")
    return Report(html_page(title, c.path, c.sha256, toc + "\n".join(body) + model_limits_html()
                            + signoff_html(revision, c.path, c.sha256), doc), summary, v)
