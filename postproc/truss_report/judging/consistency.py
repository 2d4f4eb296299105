"""truss_report.judging.consistency: what the campaign file stores in /stats against what the
report recomputes from /runs: the status counts and n_runs / n_ok / n_failed exactly, the six
outputs' statistics and the per-bay lock-time statistics to AGREE_RTOL of the column's largest
|value| (order statistics and moments apart: sums in another order round differently)."""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..reading.campaign import Campaign
from ..reading.schema import STATS_FIELDS
from .runs import LockStats, OutputStats
from .stats import AGREE_RTOL, StatsComparison

OUTPUTS_CHECK = "the six outputs recomputed vs /stats/<output>"
LOCK_CHECK = "per-bay lock times recomputed vs /stats/bays/lock_time_s (count, P5, P50, P95)"


@dataclass
class Check:
    """One check: its name, whether it passed, and what it compared: "status" (the counts by
    status), "attrs" (n_runs, n_ok, n_failed), or a StatsComparison's "counts", "order" or
    "moments" of `source` ("stats": the outputs, "lock": the lock times)."""
    what: str
    passed: bool
    part: str
    source: str = ""
    comparison: StatsComparison | None = None


def status_checks(c: Campaign, counted: Mapping[int, int]) -> list[Check]:
    codes = sorted(c.status_name)
    names_agree = all(k < len(c.stats_status_names) and c.stats_status_names[k] == c.status_name[k]
                      for k in codes)
    counts_agree = (names_agree and len(c.stats_status_counts) == len(codes)
                    and all(int(c.stats_status_counts[k]) == counted[k] for k in codes))
    n_ok = counted[0]
    attrs_agree = (c.stats_attrs["n_ok"] == n_ok and c.stats_attrs["n_failed"] == c.n - n_ok
                   and c.stats_attrs["n_runs"] == c.n)
    return [Check("status counts: /runs/status recounted vs /stats/status_counts and status_names",
                  counts_agree, "status"),
            Check("/stats attributes n_runs, n_ok, n_failed vs /runs/status", attrs_agree, "attrs")]


def comparison_checks(comparison: StatsComparison, what: str, source: str) -> list[Check]:
    res = [Check(f"{what}: counts", comparison.count_mismatches == 0, "counts", source, comparison),
           Check(f"{what}: order statistics", comparison.order <= AGREE_RTOL, "order", source, comparison)]
    if comparison.moments is not None:
        res.append(Check(f"{what}: mean and std", comparison.moments <= AGREE_RTOL, "moments", source,
                         comparison))
    return res


def compare_outputs(c: Campaign, outputs: Mapping[str, OutputStats]) -> StatsComparison:
    comparison = StatsComparison()
    for key, o in outputs.items():
        comparison.add(o.mine, c.stats[key], float(np.max(np.abs(o.x))) if len(o.x) else 0.0,
                       STATS_FIELDS)
    return comparison


def compare_lock(c: Campaign, lock: LockStats) -> StatsComparison:
    comparison = StatsComparison()
    lock_ok = c.lock[c.ok]
    lt = lock.times
    for j in range(c.lock.shape[1]):
        col = lock_ok[:, j][np.isfinite(lock_ok[:, j])]
        comparison.add({s: lt[s][j] for s in lt}, {s: c.stats_lock[s][j] for s in lt},
                       float(np.max(np.abs(col))) if len(col) else 0.0, list(lt))
    return comparison


def consistency_checks(c: Campaign, counted: Mapping[int, int], outputs: Mapping[str, OutputStats],
                       lock: LockStats) -> list[Check]:
    """Every check, in the order the report lists them."""
    return (status_checks(c, counted)
            + comparison_checks(compare_outputs(c, outputs), OUTPUTS_CHECK, "stats")
            + comparison_checks(compare_lock(c, lock), LOCK_CHECK, "lock"))
