"""truss_report.sections_free: the rail-miss probability of a free-stack campaign (docs/model.md §2
"free"): the share of runs whose pin never reached the rail, with its exact (Clopper-Pearson)
95 % interval, and the distribution of the missing hinge's closest approach to the rail."""
import numpy as np

from .page import num, table
from .stats import clopper_pearson, percentile


def section_rail_miss(c):
    """Empty unless the file has rail-miss runs and the closest-approach column."""
    codes = [k for k, v in c.status_name.items() if v == "rail miss"]
    miss = np.isin(c.status, codes)
    k = int(miss.sum())
    if k == 0 or c.rail_approach is None:
        return ""
    n = c.n
    lo, hi = clopper_pearson(k, n)
    x = c.rail_approach[miss & np.isfinite(c.rail_approach)]
    u = c.rail_approach_unit
    rows = [["runs", num("railmiss.n_runs", n)],
            ["runs ending in rail miss", num("railmiss.n_miss", k)],
            ["probability of a rail miss", num("railmiss.p", k / n, digits=4)],
            ["95 % Clopper-Pearson interval, low", num("railmiss.p.ci_lo", lo, digits=4)],
            ["95 % Clopper-Pearson interval, high", num("railmiss.p.ci_hi", hi, digits=4)]]
    if len(x):
        for name, q in (("min", 0), ("p05", 5), ("median", 50), ("p95", 95), ("max", 100)):
            rows.append([f"closest approach of the hinge to the rail, {name}",
                         num(f"railmiss.approach.{name}", percentile(x, q), u)])
    return ('<section id="railmiss"><h3>Rail miss (free stack)</h3><p>A run misses the rail '
            "when the pin of its deploying bay never reaches it (docs/model.md §2). The probability is "
            "rail-miss runs / all runs, with an exact (Clopper-Pearson) 95 % interval. The closest "
            "approach is the smallest distance of the missing hinge from the rail line before "
            "the run stopped (<code>/runs/rail_miss_closest_approach_m</code>); its percentiles "
            "are Hyndman-Fan type 7 over the rail-miss runs.</p>"
            + table(["quantity", "value"], rows) + "</section>")
