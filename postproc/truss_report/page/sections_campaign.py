"""truss_report.page.sections_campaign: the campaign (its runs' outcome, failed runs,
dispersions, base scene), the peak loads and the lock timing sections of the load report."""
from functools import partial

import os

import numpy as np

from ..judging.design import RETRACT_LABELS
from ..judging.runs import failure_groups
from ..reading.schema import LEVELS, OUTPUTS
from .figures import fig_distribution, fig_lock_timing
from .html import esc, num, table, unit_label
from .numbers import fmt, message_text, resolution

FAILED_RUNS_CSV = "failed_runs.csv"


def output_label(key, direction):
    """Readable name of an output for the campaign's direction (deploy or retract)."""
    if direction == "retract" and key in RETRACT_LABELS:
        return RETRACT_LABELS[key]
    return OUTPUTS.get(key, key)


def section_campaign(page, c, j, units):
    a = c.attrs
    out = ['<section id="campaign"><h2>1. Campaign</h2>']
    rows = [
        ("name", esc(a["campaign_name"])),
        ("description", esc(a["campaign_description"])),
        ("date (end, UTC)", esc(a["end_utc"]) + f" (started {esc(a['start_utc'])})"),
        ("software", f"truss {esc(a['software_version'])}, git revision "
                     f"<code>{esc(a['git_revision'])}</code>"),
        ("MPI ranks", num("campaign.n_ranks", a["n_ranks"], tag="span")
         + " (invocation that finished the file); sessions: "
         + num("campaign.n_sessions", a["n_sessions"], tag="span")),
        ("wall time", num("campaign.wall_time_s", c.wall_time_s, "s", tag="span", at=resolution([c.wall_time_s]))
         + " (summed over the sessions)"),
        ("sampling", esc(a["sampling"])),
        ("runs", num("campaign.n_runs", a["n_runs"], tag="span")),
        ("master seed", num("campaign.master_seed", a["master_seed"], tag="span")),
        ("largest bay count", num("campaign.n_bays_max", a["n_bays_max"], tag="span")),
        ("direction, drive mode", f"{esc(a['direction'])}, {esc(a['drive_mode'])}"),
        ("results file", f"<code>{esc(os.path.abspath(c.path))}</code>"),
        ("SHA-256 of the file", f"<code>{c.sha256}</code>"),
    ]
    out.append(table(["", ""], [[f"<th>{k}</th>", v] for k, v in rows], "kv"))
    out.append(subsection_status(c, j.counted))
    out.append(subsection_failures(page, c))
    out.append(subsection_stop(c.stop, units))
    out.append(subsection_dispersions(c, units))
    out.append(subsection_base_scene(c))
    out.append("</section>")
    return "\n".join(out)


def subsection_status(c, counted):
    codes = sorted(c.status_name)
    rows = []
    for k in codes:
        name = c.status_name[k]
        from_stats = (int(c.stats_status_counts[k]) if k < len(c.stats_status_counts)
                      else float("nan"))
        rows.append([esc(name), num(f"status_count.{name}", counted[k]),
                     num(f"status_count.{name}.stats", from_stats)])
    n_ok = counted[0]
    rows.append(["<b>all runs</b>", num("runs.n_total", c.n), num("runs.n_total.stats",
                                                                 c.stats_attrs["n_runs"])])
    return ("<h3>Outcome of the runs</h3>"
            f"<p>{num('runs.n_ok', n_ok, tag='span')} runs ok, "
            f"{num('runs.n_failed', c.n - n_ok, tag='span')} failed, of "
            f"{c.n} runs. Counts by status, from <code>/runs/status</code> and as stored in "
            "<code>/stats/status_counts</code>:</p>"
            + table(["status", "runs (counted in /runs/status)", "runs (/stats/status_counts)"],
                    rows, "narrow"))


def subsection_failures(page, c):
    """The failed runs grouped by status and message; every failed run with its full message goes
    to FAILED_RUNS_CSV beside the report (a list of thousands of rows is no page to sign)."""
    failed = np.nonzero(~c.ok)[0]
    if len(failed) == 0:
        return "<h3>Failed runs</h3><p>No run failed.</p>"
    rows, attrs = [], []
    for g, (status, tmpl, runs) in enumerate(failure_groups(c)):
        shown = ", ".join(map(str, runs[:30])) + (f", … (+{len(runs) - 30} more)"
                                                  if len(runs) > 30 else "")
        rows.append([esc(status), num(f"failure_group.{g}.count", len(runs)),
                     f"<code>{esc(tmpl)}</code>", shown,
                     f"<small>run {runs[0]}: {esc(message_text(c.messages[runs[0]]))}</small>"])
        attrs.append(f'data-status="{esc(status)}" data-runs="{" ".join(map(str, runs))}"')
    page.text_file(FAILED_RUNS_CSV, failed_runs_csv(c, failed))
    return ("<h3>Failed runs</h3><p>Failure reasons from <code>/runs/message</code>, grouped by "
            "status and by the message with its numbers replaced by <code>#</code>; run indices "
            "are 0-based rows of <code>/runs</code>.</p>"
            + table(["status", "runs", "reason (numbers as #)", "run indices", "example"],
                    rows, "", attrs)
            + f"<p>Every failed run ({len(failed)}) with its full message: <a href='{FAILED_RUNS_CSV}'>"
            f"<code>{FAILED_RUNS_CSV}</code></a> beside this report (run_index, status, message).</p>")


def failed_runs_csv(c, failed):
    """run_index, status, message of each failed run (messages quoted, quotes doubled)."""
    rows = "".join(f'{i},{c.status_name[int(c.status[i])]},"{c.messages[i].replace(chr(34), chr(34) * 2)}"\n'
                   for i in failed)
    return "run_index,status,message\n" + rows


def param_units(d):
    """Units of a dispersion's distribution parameters (the draw x, before it is applied)."""
    if d.distribution == "lognormal":
        return "1 (of ln X)"
    return "1 (relative)" if d.apply == "relative" else d.units


def subsection_dispersions(c, units):
    if not c.dispersions:
        return "<h3>Dispersions</h3><p>The campaign disperses no key.</p>"
    rows = []
    for d in c.dispersions:
        pu = param_units(d)
        lab, f = units.get(d.key, d.units, [d.nominal]) if d.units not in ("", "1") else (d.units, 1.0)
        shown = lab if pu == d.units else pu          # parameters in the key's display unit when absolute
        parts = []
        for p, v in d.params.items():
            if d.distribution == "discrete":
                vals = ", ".join(num(f"dispersion.{d.key}.{p}.{i}", float(x), tag="span")
                                 for i, x in enumerate(np.atleast_1d(v)))
                parts.append(f"{p} = [{vals}]")
            else:
                pf = f if pu == d.units else 1.0
                parts.append(f"{p} = " + num(f"dispersion.{d.key}.{p}", v, "" if shown.startswith("1") else shown,
                                             tag="span", factor=pf))
        rows.append([f"<code>{esc(d.key)}</code>", num(f"dispersion.{d.key}.factor", d.factor),
                     esc(d.distribution), "<br>".join(parts), esc(shown), esc(d.per), esc(d.apply),
                     num(f"dispersion.{d.key}.nominal", d.nominal, lab, factor=f)])
    return ("<h3 id='dispersions'>Dispersions</h3><p>From the attributes of <code>/runs/inputs/&lt;key&gt;</code>. "
            "A draw x is applied as: absolute = x, relative = nominal (1 + x), "
            "offset = nominal + x; "
            "per bay / per frame draws are independent for each bay / frame.</p>"
            + table(["key", "factor", "distribution", "parameters", "parameter units", "per",
                     "apply", "nominal"], rows))


def subsection_base_scene(c):
    tables = []
    for tab, entries in c.base_scene.items():
        if not isinstance(entries, dict):      # a top-level key outside any table
            entries, tab = {tab: entries}, ""
        rows = []
        for k, v in entries.items():
            key = f"{tab}.{k}" if tab else k
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                rows.append([f"<code>{esc(k)}</code>", esc(v)])
            else:
                rows.append([f"<code>{esc(k)}</code>", num(f"base_scene.{key}", v)])
        tables.append(table([f"<code>[{esc(tab)}]</code>" if tab else "key", "value"], rows))
    return ("<h3 id='base-scene'>Base scene</h3><p>From the root attribute <code>base_scene_toml</code> "
            "(units are in the key names; keys left unset are not listed). The complete "
            "resolved campaign, which <code>truss-campaign</code> reads back, is "
            "<code>campaign_toml</code> below.</p>"
            + "<div class='flex'>" + "".join(tables) + "</div>"
            + "<details><summary>base_scene_toml</summary><pre id='base-scene-toml'>"
            + esc(c.attrs["base_scene_toml"]) + "</pre></details>"
            + "<details><summary>campaign_toml</summary><pre>"
            + esc(c.attrs["campaign_toml"]) + "</pre></details>")


def ci_note(sampling, confidence):
    note = ("Bounds of the percentiles are distribution-free order-statistic bounds, each one-sided at "
            f"{confidence * 100:g} % (the design-load table's upper bound is the same number): for the "
            "q-quantile, the number of runs below the true quantile is Binomial(n, q); the upper "
            "bound is x<sub>(s)</sub>, s the smallest rank with F(s − 1) ≥ "
            f"{fmt(confidence)}, the lower bound x<sub>(r)</sub>, r the smallest rank with "
            f"F(r) ≥ {fmt(1 - confidence)} (F the binomial CDF; ranks 1-based). Together they "
            f"are an interval of coverage ≥ {(2 * confidence - 1) * 100:g} %; the table gives its exact "
            "coverage. When n is too small for a bound, the table says “n too small” and gives "
            "the number of runs that bound needs (an upper bound of P99.865 at 95 % needs 2218). "
            "The bounds assume independent runs")
    if sampling == "monte_carlo":
        return note + ", which Monte Carlo sampling gives."
    if sampling == "saltelli":
        return note + (". <b>This campaign used Saltelli sampling: the runs of one block share "
                       "coordinates, so they are not independent and these bounds are not "
                       "valid; use a Monte Carlo campaign for the load percentiles.</b>")
    return note + (f". With {esc(sampling)} sampling the runs are stratified rather than "
                   "independent; the bounds are then usually conservative, but this is not "
                   "guaranteed.")


def section_loads(page, c, e, j, units, confidence):
    out = ['<section id="loads"><h2>2. Peak loads and deployment time</h2>',
           "<p>Statistics over the ok runs with a finite value only (the runs that "
           "<code>/stats/&lt;output&gt;/count</code> counts). Percentiles are linear "
           "interpolation between order statistics (Hyndman-Fan type 7, "
           "<code>numpy.percentile</code>'s default), the definition of <code>/stats</code>; "
           "each is shown next to the value stored in <code>/stats</code>. Standard deviations "
           "use ddof = 1. Each load is shown in the unit of the design-load table.</p>",
           f"<p>{ci_note(c.attrs['sampling'], confidence)}</p>"]
    for key in OUTPUTS:
        out.append(output_block(page, c, j.outputs[key], output_label(key, c.direction),
                                e.nominal_value(key), units, confidence))
    out.append("</section>")
    return "\n".join(out)


def output_block(page, c, o, word, nominal, units, confidence):
    """Histogram, exceedance probability and tables of one output (o: its OutputStats)."""
    key, x, mine, stored = o.key, o.x, o.mine, c.stats[o.key]
    u, f = units.get(key, c.units[key], x)
    at = units.at(key)
    head = (f'<h3 id="{key}">{esc(word[0].upper() + word[1:])}{unit_label(u)} '
            f"<small><code>{key}</code></small></h3>")
    n_ok = int(c.ok.sum())
    if len(x) == 0:
        return (head + f"<p class='note'>No ok run has a finite value of <code>{key}</code> "
                f"({num(f'{key}.count', 0, tag='span')} values from {n_ok} ok runs): nothing to "
                f"show (the {esc(c.attrs['drive_mode'])} drive mode may not define it).</p>")
    cis, est = o.cis, o.est
    fig = partial(fig_distribution, page.plt, x / f, word, u, {k: v / f for k, v in est.items()},
                           {k: v.scaled(f) for k, v in cis.items()}, nominal / f, confidence, at)
    parts = [head,
             f"<p>{num(f'{key}.count', len(x), tag='span')} ok runs with a finite value "
             f"(of {n_ok} ok runs and {c.n} runs).</p>",
             page.figure(fig, f"dist_{key}.png",
                         f"{word}: histogram and exceedance probability "
                         f"(1 − ECDF, log scale) with P50, P95, P99, P99.865 and their one-sided "
                         f"{confidence * 100:g} % bounds")]
    summary = [[num(f"{key}.{s}", mine[s], u, factor=f, at=at) for s in ("mean", "std", "min", "max")],
               [num(f"{key}.{s}.stats", stored[s], u, factor=f, at=at)
                for s in ("mean", "std", "min", "max")]]
    summary[0].insert(0, "recomputed")
    summary[1].insert(0, "<code>/stats</code>")
    parts.append(table(["", "mean", "std (ddof 1)", "min", "max"], summary, "narrow"))
    rows = []
    for q, name, lab in LEVELS:
        ci = cis[name]
        rows.append([
            lab, num(f"{key}.{name}", est[name], u, factor=f, at=at),
            num(f"{key}.{name}.stats", stored[name], u, factor=f, at=at),
            ci_cell(f"{key}.{name}.ci_lo", ci.lo, ci.n_needed_lo, u, f, at),
            ci_cell(f"{key}.{name}.ci_hi", ci.hi, ci.n_needed_hi, u, f, at),
            (num(f"{key}.{name}.ci_r", ci.r) if ci.r is not None else "<td>—</td>"),
            (num(f"{key}.{name}.ci_s", ci.s) if ci.s is not None else "<td>—</td>"),
            num(f"{key}.{name}.ci_coverage", ci.coverage, digits=4)])
    conf = f"{confidence * 100:g} %"
    parts.append(table(["percentile", "estimate", "<code>/stats</code>", f"lower {conf} bound",
                        f"upper {conf} bound", "rank r", "rank s", "coverage of [lower, upper]"],
                       rows))
    return "\n".join(parts)


def ci_cell(key, v, n_needed, unit, factor=1.0, at=None):
    if n_needed is None:
        return num(key, v, unit, factor=factor, at=at)
    return (f'<td class="num toosmall" data-key="{esc(key)}" data-value="nan">n too small '
            f'(needs n ≥ {num(key + ".n_needed", n_needed, tag="span")})</td>')


def section_lock_timing(page, c, lock):
    words = ("unlock", "unlocks") if c.direction == "retract" else ("lock", "locks")
    u = c.units["lock_time_s"]
    order, dt_text, lt, it = lock.order, lock.interval_text, lock.times, lock.intervals
    nb = c.lock.shape[1]
    bays = np.arange(1, nb + 1)
    fig = partial(fig_lock_timing, page.plt, bays, lt, it, u, words, dt_text)
    at = {name: band_resolution(band) for name, band in (("lock", lt), ("interval", it))}
    rows = []
    for j in range(nb):
        b = j + 1
        rows.append([str(b), num(f"lock_time_s.bay{b}.count", int(lt["count"][j]))]
                    + [num(f"lock_time_s.bay{b}.{s}", lt[s][j], u, at=at["lock"]) for s in ("p5", "p50", "p95")]
                    + [num(f"lock_interval_s.bay{b}.count", int(it["count"][j]))]
                    + [num(f"lock_interval_s.bay{b}.{s}", it[s][j], u, at=at["interval"])
                       for s in ("p5", "p50", "p95")])
    return (f'<section id="locks"><h2>3. {words[0].capitalize()} timing</h2>'
            f"<p>Per bay, over the ok runs that have that bay with a finite {words[0]} time "
            f"(<code>/runs/bays/lock_time_s</code>): median and the 5–95 % band of the "
            f"{words[0]} time, and of the time between successive {words[1]}. Bay order in the "
            f"data: <b>{order}</b>; interval at {esc(dt_text)}. Percentiles as in section 2.</p>"
            + page.figure(fig, "lock_timing.png",
                          f"{words[0]} time and time between successive {words[1]} per bay: "
                          "median and 5–95 % band")
            + "<details><summary>per-bay table</summary>"
            + table(["bay", "runs", f"{words[0]} time P5", "P50", "P95", "runs",
                     "interval P5", "P50", "P95"], rows, "narrow",
                    [f'data-order="{order}"'] * len(rows))
            + "</details></section>")


def band_resolution(band):
    """The resolution of per-bay percentiles (count, p5, p50, p95 per bay): from the median width
    of their 5-95 % bands, the spread of the runs at a bay."""
    width = band["p95"] - band["p5"]
    width = width[np.isfinite(width)]
    return resolution(np.concatenate([band["p5"], band["p95"]]), float(np.median(width)) if len(width) else np.nan)


def subsection_stop(s, units):
    """The rounds of a sequentially stopped campaign and why it stopped (empty without /stop)."""
    if s is None:
        return ""
    u, f = units.get(str(s.attrs["output"]), s.unit, s.estimate)
    at = resolution(s.estimate / f, float(np.nanmedian(s.upper - s.estimate)) / f)
    rows = [[str(k), num(f"stop.round{k}.runs", int(s.runs[k])), num(f"stop.round{k}.used", int(s.used[k])),
             num(f"stop.round{k}.estimate", float(s.estimate[k]), u, factor=f, at=at),
             num(f"stop.round{k}.upper", float(s.upper[k]), u, factor=f, at=at),
             num(f"stop.round{k}.width", float(s.achieved_width[k]), digits=3), esc(s.rounds_state[k])]
            for k in range(len(s.runs))]
    what = (f"the one-sided {fmt(100 * s.attrs['confidence'])} % bound of the {fmt(s.attrs['level'])} quantile of "
            f"<code>{esc(s.attrs['output'])}</code> within {fmt(s.attrs['width'])} of it (relative)"
            if s.attrs["target"] == "percentile_bound" else
            f"the {esc(s.attrs['target'].replace('_', ' '))} of the share of runs that are not ok at most {fmt(s.attrs['width'])}")
    return ("<h3>Sequential stopping</h3><p>The campaign ran in rounds until " + what + f", at most "
            f"{s.attrs['max_runs']} runs (<code>/stop</code>). It stopped: <b>{esc(s.attrs['state'])}</b>, "
            f"{esc(s.attrs['reason'])}.</p>"
            + table(["after round", "runs", "values used", "estimate", "upper bound", "achieved width", "state"],
                    rows, "narrow"))
