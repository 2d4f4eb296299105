"""truss_report.page.sections_importance: the report of a standalone cross-entropy importance-sampling
campaign (ensemble.method = "importance", the file's /importance, docs/hdf5-schema.md): the
failure probability with its 95 % interval and one-sided upper bound, CoV, ESS, Pareto k, the
runs, the refusal and its reason; the cross-entropy levels; the adapted density's mean shift per
input (which inputs drive the failure). The runs are draws of a density moved to the failure, not
of the dispersions, so the page has no design loads and no run-share probabilities."""
from ..judging.importance import calc_input_shifts
from .html import esc, html_page, num, table
from .numbers import LEAST, fmt, message_text, p_digits, readable_unit, resolution
from .render import Report
from .sections_subset import event_text, margin_text
from .top import campaign_doc, model_limits_html, signoff_html


def p_text_digits(s):
    return p_digits(s.p, s.lower, s.upper)


def refusal_html(s):
    if not s.refused:
        return ""
    return (f"<p class='warn'>The estimate is <b>refused</b>: {esc(message_text(s.refused))}. "
            "It is not to be used: p below is the weighted mean of the final runs as stored, without "
            "an interval; run more final runs (n_final), or subset simulation where the failure has "
            "many small causes.</p>")


def unusable_html(s):
    if s.unusable <= 0:
        return ""
    return (f"<p class='warn'>{s.unusable} runs gave no margin (a cap or a failure before the event) and the "
            "estimate counts them as safe: p may lie below the failure probability.</p>")


def section_probability(s):
    d = p_text_digits(s)
    conf = fmt(100 * float(s.attrs["confidence"]), LEAST)
    rows = [["failure probability p", num("importance.p", s.p, digits=d)],
            [f"{conf} % interval, low (lognormal with the CoV)", num("importance.p.ci_lo", s.lower, digits=d)],
            [f"{conf} % interval, high", num("importance.p.ci_hi", s.upper, digits=d)],
            [f"one-sided {conf} % upper bound", num("importance.p.upper_bound", s.upper_bound, digits=d)],
            ["coefficient of variation (sample, weighted final runs)", num("importance.cov", s.cov, digits=2)],
            ["effective sample size of the failing final runs (Kish)", num("importance.ess", s.ess, digits=3)],
            ["Pareto k of their weights (above 0.7: refused)", num("importance.pareto_k", s.pareto_k, digits=2)],
            ["failing final runs", num("importance.failures", s.failures)],
            ["final runs (the estimate's)", num("importance.final_runs", s.final_runs)],
            ["runs used (levels and final)", num("importance.runs", s.runs)],
            ["cross-entropy levels", num("importance.levels", len(s.levels["threshold"]))]]
    return ("<section id='probability'><h2>Failure probability</h2>"
            f"<p>Failure event: {event_text(s)}, estimated by cross-entropy importance sampling "
            f"(Rubinstein 1997; Kurtz &amp; Song 2013) with {s.attrs['n_per_level']} runs a level, "
            f"rho = {fmt(float(s.attrs['rho']))} and {s.attrs['n_final']} final runs from the adapted "
            "density, on which alone the estimate rests (p: the mean of the failing runs' weights "
            f"φ(z) / h(z)). Status <b>{esc(s.status)}</b>: {esc(message_text(s.attrs['message']))}.</p>"
            + refusal_html(s) + unusable_html(s)
            + table(["quantity", "value"], rows, "narrow") + "</section>")


def section_levels(s):
    L = s.levels
    n = len(L["threshold"])
    u, f = readable_unit(s.level_units, float(max(abs(L["threshold"]))) if n else float("nan"))
    at = resolution(L["threshold"] / f) if n else None
    rows = [[str(i), num(f"importance.level{i}.threshold", float(L["threshold"][i]), u, factor=f, at=at),
             num(f"importance.level{i}.shift", float(L["shift"][i]), "σ", digits=3),
             num(f"importance.level{i}.moved", int(L["moved"][i])),
             num(f"importance.level{i}.elites", int(L["elites"][i])),
             num(f"importance.level{i}.elite_ess", float(L["elite_ess"][i]), digits=3),
             num(f"importance.level{i}.runs", int(L["runs"][i])),
             num(f"importance.level{i}.unusable", int(L["unusable"][i]))] for i in range(n)]
    return ("<section id='levels'><h2>Cross-entropy levels</h2><p>Each level draws its runs from the "
            "density N(μ, I) in the standard normal space of the dispersions; its threshold is the "
            "share rho of its smallest margins (0 once the failure is reached), and μ moves to the "
            "weighted mean of those elite runs, a component only where it moved by more than 3 "
            "standard errors (moved: how many). The shift is |μ| of the density the level drew from, "
            "in standard deviations (σ).</p>"
            + table(["level", "threshold", "density shift |μ|", "moved", "elites", "elite ESS", "runs",
                     "unusable"], rows, "narrow") + "</section>")


def section_inputs(s, c):
    shifts = calc_input_shifts(s, c)
    if shifts is None:
        return ("<section id='inputs'><h2>What drives the failure</h2><p>The final density's mean "
                f"has {len(s.final_mean)} components, not one per dimension of the file's dispersions: "
                "not shown.</p></section>")
    rows = []
    for r in shifts:
        per = "" if r.width == 1 else f" (mean over {r.width} {'bays' if r.per == 'bay' else 'frames'})"
        rows.append([f"<code>{esc(r.key)}</code>{per}", num(f"importance.mu.{r.key}.nominal", r.nominal, r.unit),
                     num(f"importance.mu.{r.key}.shift", r.shift, "σ", digits=3),
                     num(f"importance.mu.{r.key}.value", r.value, r.unit)])
    return ("<section id='inputs'><h2>What drives the failure</h2><p>The adapted density's mean μ "
            "(<code>/importance/final_mean</code>) per dispersed input, in standard deviations of the "
            "input's law, and the input's value there in its own unit: the inputs the failure needs "
            "moved come first (largest |μ|); an input left at 0 σ does not lead to it.</p>"
            + table(["input", "nominal", "mean shift μ", "value at μ"], rows, "narrow") + "</section>")


def terminal_lines(c, s):
    d = p_text_digits(s)
    kind = s.attrs["failure_kind"]
    event = (f"{s.attrs['failure_column']} <= 0 {s.attrs['margin_units']}" if kind == "margin" else
             f"{s.attrs['failure_column']} {'>=' if kind == 'above' else '<='} "
             f"{margin_text(float(s.attrs['failure_threshold']), s)}")
    head = f"IMPORTANCE SAMPLING ({c.attrs['campaign_name']}, {s.runs} runs, {s.status}): P({event}) = {fmt(s.p, d)}"
    if s.refused:
        return [head, f"  REFUSED, not to be used: {s.refused}"]
    return [head, f"  95 % interval [{fmt(s.lower, d)}, {fmt(s.upper, d)}], upper bound {fmt(s.upper_bound, d)}, "
                  f"CoV {fmt(s.cov, 2)}, ESS {fmt(s.ess, 3)}, Pareto k {fmt(s.pareto_k, 2)}"]


def importance_report(c, s, revision, nominal_html):
    """The report of a standalone importance campaign, with its lines for the terminal (no verdict)."""
    toc = ("<nav><a href='#probability'>Failure probability</a> · <a href='#levels'>Cross-entropy levels</a> · "
           "<a href='#inputs'>What drives the failure</a> · <a href='#nominal'>Nominal run</a> · "
           "<a href='#limits'>Model limits</a> · <a href='#signoff'>Sign-off</a></nav>")
    body = [section_probability(s), section_levels(s), section_inputs(s, c), nominal_html]
    title = f"Failure-probability report: campaign “{c.attrs['campaign_name']}”"
    state = f"refused, not to be used: {s.refused}" if s.refused else s.status
    verdict = (f"none: a failure-probability estimate, p = {esc(fmt(s.p, p_text_digits(s)))} "
               f"({esc(message_text(state))})")
    return Report(html_page(title, c.path, c.sha256, toc + "\n".join(body) + model_limits_html()
                            + signoff_html(revision, c.path, c.sha256), campaign_doc(c, verdict)),
                  terminal_lines(c, s), None)
