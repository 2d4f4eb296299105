"""truss_report.page.sections_free: the rail-miss probability of a free-stack campaign (docs/model.md §2
"free"): the share of runs whose pin never reached the rail, with its exact (Clopper-Pearson)
95 % interval, and the distribution of the missing hinge's closest approach to the rail."""
from ..judging.runs import rail_miss
from .html import num, table


def section_rail_miss(c):
    """Empty unless the file has rail-miss runs and the closest-approach column."""
    r = rail_miss(c)
    if r is None:
        return ""
    n, k, lo, hi = r.n, r.k, r.lo, r.hi
    u = c.rail_approach_unit
    rows = [["runs", num("railmiss.n_runs", n)],
            ["runs ending in rail miss", num("railmiss.n_miss", k)],
            ["probability of a rail miss", num("railmiss.p", k / n, digits=4)],
            ["95 % Clopper-Pearson interval, low", num("railmiss.p.ci_lo", lo, digits=4)],
            ["95 % Clopper-Pearson interval, high", num("railmiss.p.ci_hi", hi, digits=4)]]
    for name, v in r.approach.items():
        rows.append([f"closest approach of the hinge to the rail, {name}",
                     num(f"railmiss.approach.{name}", v, u)])
    return ('<section id="railmiss"><h3>Rail miss (free stack)</h3><p>A run misses the rail '
            "when the pin of its deploying bay never reaches it (docs/model.md §2). The probability is "
            "rail-miss runs / all runs, with an exact (Clopper-Pearson) 95 % interval. The closest "
            "approach is the smallest distance of the missing hinge from the rail line before "
            "the run stopped (<code>/runs/rail_miss_closest_approach_m</code>); its percentiles "
            "are Hyndman-Fan type 7 over the rail-miss runs.</p>"
            + table(["quantity", "value"], rows) + "</section>")
