"""truss_report.judging.stats: percentiles (type 7, as /stats), distribution-free order-statistic
bounds, Clopper-Pearson intervals, Spearman rank correlations, the /stats fields of a column,
the comparison of recomputed statistics with /stats, and the lock order and intervals."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.stats import beta as beta_dist
from scipy.stats import binom, rankdata, spearmanr

from ..reading.h5file import Array
from ..reading.schema import STATS_PERCENTILES

CONFIDENCE = 0.95

# A statistic in /stats and its recomputation here agree when they differ by at most this much,
# relative to the largest |value| of the column: the same formula on the same float64 data, where
# only the order of the roundings may differ (sums: about n ulps of the largest value). Counts
# must agree exactly.
AGREE_RTOL = 1e-9


def percentile(x: Array, q: float) -> float:
    """Hyndman-Fan type 7 (numpy.percentile's default, linear), as /stats defines it."""
    return float(np.percentile(x, q))


@dataclass
class QuantileCI:
    """Distribution-free bounds x_(r) <= quantile <= x_(s) of a quantile, each one-sided at the
    confidence (1-based ranks; None: the sample is too small for that bound)."""
    lo: float
    hi: float
    r: int | None
    s: int | None
    coverage: float       # P(x_(r) <= true quantile < x_(s)), missing bounds taken as -+inf
    n_needed_lo: int | None  # smallest n giving a lower bound (reported when r is None)
    n_needed_hi: int | None

    def scaled(self, factor: float) -> QuantileCI:
        """The same bounds in a display unit (value / factor)."""
        return QuantileCI(self.lo / factor, self.hi / factor, self.r, self.s, self.coverage,
                          self.n_needed_lo, self.n_needed_hi)


def quantile_ci(x_sorted: Array, p: float, confidence: float = CONFIDENCE) -> QuantileCI:
    """One-sided distribution-free bounds of the p-quantile (0 < p < 1) of sorted data, each at
    `confidence`; together they are a two-sided interval of coverage >= 2 confidence - 1.

    B = #{X_i <= true quantile} is Binomial(n, p), F its CDF, a = 1 - confidence.
    Upper bound x_(s): s the smallest rank with F(s - 1) >= confidence, so that
    P(x_(s) >= quantile) = P(B <= s - 1) >= confidence (the design-load table's bound).
    Lower bound x_(r): r the smallest k with F(k) >= a, so P(x_(r) <= quantile) = 1 - F(r - 1)
    > 1 - a. r = 0 or s = n + 1 means the sample is too small for that bound: the upper one needs
    p^n <= a (2218 runs for P99.865 at 95 %).
    """
    n = len(x_sorted)
    a = 1.0 - confidence
    r = int(binom.ppf(a, n, p))
    s = int(binom.ppf(confidence, n, p)) + 1
    cov = float(binom.cdf(min(s, n + 1) - 1, n, p) - (binom.cdf(r - 1, n, p) if r >= 1 else 0.0))
    has_lo, has_hi = r >= 1, s <= n
    return QuantileCI(lo=float(x_sorted[r - 1]) if has_lo else float("nan"),
                      hi=float(x_sorted[s - 1]) if has_hi else float("nan"),
                      r=r if has_lo else None, s=s if has_hi else None, coverage=cov,
                      n_needed_lo=None if has_lo else min_runs_for_bound(p, a, "lo"),
                      n_needed_hi=None if has_hi else min_runs_for_bound(p, a, "hi"))


def min_runs_for_bound(p: float, a: float, side: str) -> int:
    """Smallest n for which quantile_ci has that bound: (1-p)^n < a (lower), p^n <= a (upper)."""
    base = 1.0 - p if side == "lo" else p
    n = max(1, int(np.floor(np.log(a) / np.log(base))))
    while not (base ** n < a if side == "lo" else base ** n <= a):
        n += 1
    while n > 1 and (base ** (n - 1) < a if side == "lo" else base ** (n - 1) <= a):
        n -= 1
    return n


def clopper_pearson(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Exact (Clopper-Pearson) interval of a binomial proportion k/n."""
    a = (1.0 - confidence) / 2.0
    lo = 0.0 if k == 0 else float(beta_dist.ppf(a, k, n - k + 1))
    hi = 1.0 if k == n else float(beta_dist.ppf(1.0 - a, k + 1, n - k))
    return lo, hi


def spearman(x: Array, y: Array) -> tuple[float, int]:
    """Spearman's rho over the pairs where both are finite; (rho, n), rho NaN if undefined."""
    m = np.isfinite(x) & np.isfinite(y)
    n = int(m.sum())
    if n < 3 or np.ptp(x[m]) == 0 or np.ptp(y[m]) == 0:
        return float("nan"), n
    return float(spearmanr(x[m], y[m])[0]), n


def spearman_table(columns: Sequence[Array], y: Array,
                   ranks_cache: dict[bytes, Any] | None = None) -> list[tuple[float, int]]:
    """[(rho, n)] of each input column with y, equal to [spearman(x, y) for x in columns] up to
    rounding: y is ranked once, and the columns that are finite wherever y is are ranked together
    and correlated with it in one matrix product (Pearson's r of the ranks); the others (NaN
    inside y's runs: bays beyond a run's bay count) go through spearman() one by one.
    ranks_cache (a dict): the columns' centred ranks, kept per set of runs, for the next output
    finite in the same runs (usually every output: the ok runs)."""
    m = np.isfinite(y)
    n = int(m.sum())
    res = [(float("nan"), n)] * len(columns)
    if not columns or n < 3 or np.ptp(y[m]) == 0:
        return [spearman(x, y) for x in columns]
    key = m.tobytes()
    if ranks_cache is None or key not in ranks_cache:
        X = np.column_stack([x[m] for x in columns])
        full = np.all(np.isfinite(X), axis=0)
        varies = full & (np.ptp(np.where(full, X, 0.0), axis=0) > 0)
        rx = rankdata(X[:, varies], axis=0) if np.any(varies) else None
        if rx is not None:
            rx -= rx.mean(axis=0)
        if ranks_cache is not None:
            ranks_cache[key] = (full, varies, rx)
    else:
        full, varies, rx = ranks_cache[key]
    if rx is not None:
        ry = rankdata(y[m])
        ry -= ry.mean()
        rho = (ry @ rx) / np.sqrt((rx * rx).sum(axis=0) * (ry @ ry))
        for j, r in zip(np.nonzero(varies)[0], rho):
            res[j] = (float(r), n)
    for j in np.nonzero(~full)[0]:
        res[j] = spearman(columns[j], y)
    return res


def scaled_diff(a: float, b: float, scale: float) -> float:
    """|a - b| / scale (scale: the largest |value| of the column); 0 when both are NaN or equal,
    inf when only one is NaN."""
    if np.isnan(a) and np.isnan(b) or a == b:
        return 0.0
    if np.isnan(a) or np.isnan(b):
        return float("inf")
    return abs(a - b) / max(scale, float(np.finfo(float).tiny))


@dataclass
class StatsComparison:
    """Recomputed statistics against /stats: counts that differ, and the largest scaled
    difference of the order statistics (min, max, percentiles) and of the moments (mean, std;
    None when none was compared)."""
    count_mismatches: int = 0
    order: float = 0.0
    moments: float | None = None

    def add(self, mine: dict[str, float], stored: dict[str, float], scale: float,
            fields: Sequence[str]) -> None:
        for f in fields:
            if f == "count":
                self.count_mismatches += int(mine[f] != stored[f])
            elif f in ("mean", "std"):
                self.moments = max(self.moments or 0.0, scaled_diff(mine[f], stored[f], scale))
            else:
                self.order = max(self.order, scaled_diff(mine[f], stored[f], scale))


def column_stats(x: Array) -> dict[str, float]:
    """The /stats fields of one column of finite values (NaN where undefined)."""
    nan = float("nan")
    res = {"count": len(x), "mean": float(np.mean(x)) if len(x) else nan,
           "std": float(np.std(x, ddof=1)) if len(x) >= 2 else nan,
           "min": float(np.min(x)) if len(x) else nan, "max": float(np.max(x)) if len(x) else nan}
    for name, q in STATS_PERCENTILES.items():
        res[name] = percentile(x, q) if len(x) else nan
    return res


def lock_order(lock_ok: Array) -> str:
    """'descending' when every run locks bay j+1 before bay j (the top bay first),
    'ascending' for the reverse, 'mixed' otherwise (from the finite consecutive differences)."""
    d = np.diff(lock_ok, axis=1)
    d = d[np.isfinite(d)]
    if len(d) and np.all(d < 0):
        return "descending"
    if len(d) and np.all(d > 0):
        return "ascending"
    return "mixed"


def lock_intervals(lock: Array, order: str) -> tuple[Array, str]:
    """Per run, per bay k (1-based): the time from the previous lock to the lock of bay k
    (descending: lock(k) - lock(k+1); ascending: lock(k) - lock(k-1); mixed: lock(k+1) - lock(k),
    signed). Returns (n x n_bays_max array, NaN where undefined, and a description)."""
    dt = np.full(lock.shape, np.nan)
    if order == "descending":
        dt[:, :-1] = lock[:, :-1] - lock[:, 1:]
        return dt, ("bay k: lock of bay k minus lock of bay k+1 (bays lock from the top, "
                    "bay n first)")
    if order == "ascending":
        dt[:, 1:] = lock[:, 1:] - lock[:, :-1]
        return dt, "bay k: lock of bay k minus lock of bay k−1 (bays lock from bay 1 upwards)"
    dt[:, :-1] = lock[:, 1:] - lock[:, :-1]
    return dt, ("bay k: lock of bay k+1 minus lock of bay k, signed (the bays do not lock in one "
                "monotonic order)")


def band_stats(cols: Array) -> dict[str, Array]:
    """count, P5, P50, P95 of each column's finite values (NaN where no value)."""
    res: dict[str, list[float]] = {"count": [], "p5": [], "p50": [], "p95": []}
    for col in cols.T:
        v = col[np.isfinite(col)]
        res["count"].append(len(v))
        for name, q in (("p5", 5.0), ("p50", 50.0), ("p95", 95.0)):
            res[name].append(percentile(v, q) if len(v) else float("nan"))
    return {k: np.array(v) for k, v in res.items()}
