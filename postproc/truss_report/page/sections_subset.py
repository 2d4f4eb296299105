"""truss_report.page.sections_subset: the report of a subset-simulation campaign (ensemble.method =
"subset", the file's /subset, docs/hdf5-schema.md): the failure probability with its interval,
beta, the coefficients of variation, the runs used and the runs crude Monte Carlo would need for
the same CoV; the threshold of each level; the failure samples' inputs against nominal (which
inputs drive the failure). The runs of such a campaign are not draws of the dispersions (the
Markov chains dwell near the failure), so it has no design loads and no run-share probabilities."""
from functools import partial

import numpy as np

from ..judging.subset import (PLATEAU_SHARE, biased_low, count_plateau_levels, design_point, inputs_at_failure,
                              interval)
from .html import esc, html_page, num, table
from .numbers import LEAST, MOST, fmt, message_text, p_digits, readable_unit, resolution, unit_text
from .render import Report
from .top import campaign_doc, model_limits_html, signoff_html


def plateau_warning(n):
    """The report's sentence for n plateau levels (empty below PLATEAU_LEVELS)."""
    if not biased_low(n):
        return ""
    return (f"the margin is nearly flat over {n} levels (each threshold within {fmt(100 * PLATEAU_SHARE)} % of the "
            "previous one): the levels select on inputs that do not lead to the failure, and the estimate can lie "
            "far below the failure probability, beyond its interval; use a margin that falls towards the failure "
            "in the inputs that cause it, or check the estimate another way")


def event_text(s):
    col, kind = esc(s.attrs["failure_column"]), s.attrs["failure_kind"]
    unit = unit_text(s.attrs["margin_units"])
    if kind == "margin":
        return f"<code>{col}</code> ≤ 0 {esc(unit)}"
    return f"<code>{col}</code> {'≥' if kind == 'above' else '≤'} {esc(margin_text(s.attrs['failure_threshold'], s))}"


# What each CoV an interval may use is (docs/campaigns.md "Which CoV to read").
COV_RULES = {"bound": "the larger of Au & Beck's bound for correlated levels and the lineage estimator",
             "interval": "the lag-1 estimator blended with the bound by the surviving lineages",
             "lineage": "the lineage estimator"}


def section_probability(s):
    lo, hi = interval(s.p, s.cov_interval)
    d = p_digits(s.p, lo, hi)
    rows = [["failure probability p", num("subset.p", s.p, digits=d)],
            [f"95 % interval, low (lognormal, {s.cov_interval_name} CoV)", num("subset.p.ci_lo", lo, digits=d)],
            ["95 % interval, high", num("subset.p.ci_hi", hi, digits=d)],
            ["reliability index β = −Φ⁻¹(p)", num("subset.beta", s.beta, digits=LEAST)],
            [f"coefficient of variation of the interval ({COV_RULES.get(s.cov_interval_name, s.cov_interval_name)})",
             num("subset.cov_bound", s.cov_interval, digits=2)],
            ["coefficient of variation (lineage estimator)", num("subset.cov_lineage", s.cov_lineage, digits=2)],
            ["coefficient of variation (Au & Beck)", num("subset.cov", s.cov, digits=2)],
            ["runs used", num("subset.runs", s.runs)],
            ["levels", num("subset.levels", len(s.levels["threshold"]))],
            ["crude Monte Carlo runs for an interval as narrow", num("subset.crude_mc_runs", s.crude_mc_runs,
                                                                    digits=3)],
            ["distinct level-0 ancestors of the last level", num("subset.lineages", s.lineages)]]
    warn = ""
    plateau = plateau_warning(count_plateau_levels(s.levels["threshold"]))
    if s.status != "converged":
        warn = (f"<p class='warn'>The estimate did not converge: <b>{esc(s.status)}</b> "
                f"({esc(message_text(s.attrs['message']))}). With <code>level_cap</code> the failure was not reached "
                "within max_levels: p is at most the last level's threshold share times p0^levels; "
                "raise max_levels.</p>")
    elif plateau:
        warn = f"<p class='warn'>Biased low? {esc(plateau)}.</p>"
    elif np.sum(s.levels.get("unusable", 0)) > 0:
        warn = (f"<p class='warn'>{int(np.sum(s.levels['unusable']))} runs gave no margin (a cap or a failure "
                "before the event) and the estimate counts them as safe: p may lie below the failure "
                "probability.</p>")
    elif s.lineages < 20:
        warn = (f"<p class='warn'>Only {s.lineages} level-0 ancestors survive to the last level: "
                "the lineage and Au &amp; Beck CoVs then understate the spread (the interval uses the "
                "larger bound); raise "
                "n_per_level.</p>")
    return ("<section id='probability'><h2>Failure probability</h2>"
            f"<p>Failure event: {event_text(s)}, estimated by subset simulation (Au &amp; Beck "
            f"2001) with {s.attrs['n_per_level']} samples a level and p0 = {fmt(s.attrs['p0'])}. Status "
            f"<b>{esc(s.status)}</b>: {esc(message_text(s.attrs['message']))}.</p>" + warn
            + table(["quantity", "value"], rows, "narrow") + "</section>")


def fig_levels(plt, s):
    th, pr = s.levels["threshold"], s.levels["probability"]
    k = np.arange(len(th))
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11.0, 3.8))
    a1.plot(k, th, "o-", color="C0")
    a1.axhline(0.0, color="C3", lw=1, ls="--", label="failure (margin 0)")
    a1.set_xlabel("level")
    a1.set_ylabel(f"threshold ({s.level_units})")
    a1.set_xticks(k)
    a1.legend()
    a2.semilogy(k, np.cumprod(pr), "o-", color="C1", label="P(margin ≤ threshold)")
    a2.axhline(s.p, color="C3", lw=1, ls="--", label=f"p = {fmt(s.p, p_digits(s.p, *interval(s.p, s.cov_interval)))}")
    a2.set_xlabel("level")
    a2.set_ylabel("probability")
    a2.set_xticks(k)
    a2.legend()
    fig.tight_layout()
    return fig


def section_levels(page, s):
    L = s.levels
    u, f = readable_unit(s.level_units, float(np.max(np.abs(L["threshold"]))) if len(L["threshold"]) else np.nan)
    at = resolution(L["threshold"] / f)
    rows = [[str(i), num(f"subset.level{i}.threshold", float(L["threshold"][i]), u, factor=f, at=at),
             num(f"subset.level{i}.probability", float(L["probability"][i]), digits=LEAST),
             num(f"subset.level{i}.acceptance", float(L["acceptance"][i]), digits=2),
             num(f"subset.level{i}.runs", int(L["runs"][i])),
             num(f"subset.level{i}.unusable", int(L["unusable"][i]))] for i in range(len(L["threshold"]))]
    return ("<section id='levels'><h2>Levels</h2><p>Each level keeps the samples whose margin is at "
            "or below its threshold (a share p0 of them, more with ties); the last level's "
            "threshold is the failure itself. The acceptance rate is the share of Markov steps "
            "that moved (0.2–0.8 is healthy; near 0 the chains stall and the CoV understates). "
            "Unusable runs could not give a margin (a stall before the event) and count as safe.</p>"
            + page.figure(partial(fig_levels, page.plt, s), "subset_levels.png",
                          "threshold of each level (left) and the probability of reaching it (right)")
            + table(["level", "threshold", "share", "acceptance", "runs", "unusable"], rows, "narrow")
            + "</section>")


def design_point_rows(s, c):
    """Per dispersed key: nominal, the population's median (level 0: draws of the dispersions),
    the failure samples' median, their mean standard-normal coordinate."""
    rows = []
    for r in inputs_at_failure(s, c):
        per = "" if r.width == 1 else f" (mean over {r.width} {'bays' if r.per == 'bay' else 'frames'})"
        rows.append([f"<code>{esc(r.key)}</code>{per}", num(f"subset.dp.{r.key}.nominal", r.nominal, r.unit),
                     num(f"subset.dp.{r.key}.population", r.population, r.unit),
                     num(f"subset.dp.{r.key}.failure", r.failure, r.unit),
                     num(f"subset.dp.{r.key}.z", r.mean_z, digits=3)])
    return rows


def design_point_html(dp, s):
    rows = []
    for r in dp.rows:
        per = "" if r.width == 1 else f" (mean over {r.width} {r.per}s)"
        k = r.key
        rows.append([f"<code>{esc(k)}</code>{per}", num(f"subset.mpp.{k}.nominal", r.nominal, r.unit),
                     num(f"subset.mpp.{k}.value", r.value, r.unit, digits=MOST),
                     num(f"subset.mpp.{k}.z", r.z, digits=3),
                     num(f"subset.mpp.{k}.alpha", r.alpha, digits=3),
                     num(f"subset.mpp.{k}.share", r.share, digits=3)])
    return ("<h3>Design point (most probable failure point)</h3>"
            f"<p>Of the failure samples, the one of highest standard-normal density (smallest "
            f"|z|): run {dp.run}, margin {margin_text(dp.margin, s)}, "
            "|z*| = " + num("subset.mpp.beta", dp.beta, digits=LEAST, tag="span")
            + f" (the FORM index it gives, against β = {fmt(s.beta, LEAST)} from p). Its inputs "
            "in physical units, and each input's importance: the direction cosines α<sub>i</sub> "
            "= −z*<sub>i</sub> / |z*| of the design point (α &lt; 0: the input must rise for the "
            "failure), and α<sup>2</sup>, the input's share of |z*|<sup>2</sup> (the shares sum "
            "to 1; for a per-bay or per-frame dispersion, summed over its bays or frames, whose "
            "α is then shown as —). Sorted by share.</p>"
            + table(["input", "nominal", "at the design point", "z* (σ)", "α", "α²"], rows, "narrow"))


def section_design_point(s, c):
    n = len(s.failure_runs)
    if n == 0:
        return ("<section id='designpoint'><h2>Failure samples</h2><p>No failing sample: the "
                "estimate did not reach the failure.</p></section>")
    dp = design_point(s, c)
    return ("<section id='designpoint'><h2>What drives the failure</h2>"
            + (design_point_html(dp, s) if dp else "")
            + "<h3>Failure samples against the population</h3>"
            f"<p>The {n} distinct failing points of the last level (<code>/subset/failure_samples</code>) "
            "against the nominal and the population (the median over level 0, plain draws of the "
            "dispersions). The last column is the failure samples' mean coordinate in the standard "
            "normal space of the dispersions: how many standard deviations from its median a "
            "dispersion must go for the failure; sorted by its size, the inputs that drive the "
            "failure come first.</p>"
            + table(["input", "nominal", "population median", "failure samples' median",
                     "mean z (σ)"], design_point_rows(s, c)) + "</section>")


def margin_text(v, s):
    """A margin of the failure event in its display unit ("-0.12 mm"), as declared values are."""
    u, f = readable_unit(s.attrs["margin_units"], abs(v))
    return f"{fmt(v / f)} {u}"


def terminal_lines(c, s):
    lo, hi = interval(s.p, s.cov_interval)
    d = p_digits(s.p, lo, hi)
    kind = s.attrs["failure_kind"]
    event = (f"{s.attrs['failure_column']} <= 0 {unit_text(s.attrs['margin_units'])}" if kind == "margin" else
             f"{s.attrs['failure_column']} {'>=' if kind == 'above' else '<='} {margin_text(s.attrs['failure_threshold'], s)}")
    return [f"SUBSET SIMULATION ({c.attrs['campaign_name']}, {s.runs} runs, {s.status}): P({event}) = {fmt(s.p, d)}",
            f"  95 % interval [{fmt(lo, d)}, {fmt(hi, d)}], beta = {fmt(s.beta, LEAST)}, CoV "
            f"{fmt(s.cov_interval, 2)} ({s.cov_interval_name}; lineage {fmt(s.cov_lineage, 2)}, Au & Beck "
            f"{fmt(s.cov, 2)}); crude Monte Carlo "
            f"would need {fmt(s.crude_mc_runs, 2)} runs"] + design_point_lines(c, s)


def design_point_lines(c, s):
    dp = design_point(s, c)
    if dp is None:
        return []
    top = []
    for r in dp.rows[:3]:
        u, f = readable_unit(r.unit, abs(r.value))
        top.append(f"{r.key} {fmt(r.value / f)} {u} (alpha^2 {fmt(r.share, 2)})")
    return [f"  design point (failure sample of smallest |z|, run {dp.run}): |z*| = "
            f"{fmt(dp.beta, LEAST)}; {', '.join(top)}"]


def subset_report(page, c, s, revision, nominal_html):
    """The report of a subset campaign, with its lines for the terminal (no verdict)."""
    toc = ("<nav><a href='#probability'>Failure probability</a> · <a href='#levels'>Levels</a> · "
           "<a href='#designpoint'>What drives the failure</a> · <a href='#nominal'>Nominal run</a> · "
           "<a href='#limits'>Model limits</a> · <a href='#signoff'>Sign-off</a></nav>")
    body = [section_probability(s), section_levels(page, s), section_design_point(s, c), nominal_html]
    title = f"Failure-probability report: campaign “{c.attrs['campaign_name']}”"
    verdict = (f"none: a failure-probability estimate, p = {esc(fmt(s.p, p_digits(s.p, *interval(s.p, s.cov_interval))))} "
               f"({esc(s.status)})")
    return Report(html_page(title, c.path, c.sha256, toc + "\n".join(body) + model_limits_html()
                            + signoff_html(revision, c.path, c.sha256), campaign_doc(c, verdict)),
                  terminal_lines(c, s), None)
