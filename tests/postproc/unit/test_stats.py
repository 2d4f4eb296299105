"""truss_report.judging.stats against values derived independently: type-7 percentiles written
out, order-statistic ranks from an exact binomial sum (fractions), Clopper-Pearson bounds from the
binomial tail they are defined by, Spearman's rho as Pearson's r of ranks."""
import math
from fractions import Fraction

import numpy as np
import pytest

from truss_report.judging import stats


def binom_cdf(k, n, p):
    """P(B <= k), B ~ Binomial(n, p), exactly (p a Fraction), as 1 - the upper tail (fewer terms:
    the ranks tested lie near n)."""
    return 1 - sum(Fraction(math.comb(n, i)) * p ** i * (1 - p) ** (n - i) for i in range(k + 1, n + 1))


def test_percentile_is_type_7():
    x = np.array([3.0, 1.0, 4.0, 1.5, 9.0, 2.6])
    s = np.sort(x)
    for q in (0.0, 12.5, 50.0, 95.0, 100.0):
        h = (len(s) - 1) * q / 100.0
        lo = int(math.floor(h))
        want = s[lo] + (h - lo) * (s[min(lo + 1, len(s) - 1)] - s[lo])
        assert stats.percentile(x, q) == pytest.approx(want, rel=1e-15)


@pytest.mark.parametrize("n,p", [(50, 0.9), (300, 0.99), (2300, 0.99865)])
def test_upper_bound_rank_is_the_smallest_with_enough_coverage(n, p):
    """s is the smallest rank with F(s - 1) >= 0.95, exactly."""
    x = np.arange(1.0, n + 1.0)
    ci = stats.quantile_ci(x, p, 0.95)
    pf = Fraction(p).limit_denominator(10 ** 5)
    if ci.s is None:
        assert binom_cdf(n - 1, n, pf) < Fraction(95, 100)
        return
    assert binom_cdf(ci.s - 1, n, pf) >= Fraction(95, 100) > binom_cdf(ci.s - 2, n, pf)
    assert ci.hi == x[ci.s - 1]      # the order statistic of that rank


def test_too_few_runs_for_the_upper_bound_of_p99865():
    """p^n <= 0.05 first holds at n = 2218 (ln 0.05 / ln 0.99865 = 2217.6)."""
    assert stats.min_runs_for_bound(0.99865, 0.05, "hi") == 2218
    assert 0.99865 ** 2218 <= 0.05 < 0.99865 ** 2217
    assert stats.quantile_ci(np.arange(2217.0), 0.99865).s is None
    assert stats.quantile_ci(np.arange(2218.0), 0.99865).s == 2218


@pytest.mark.parametrize("k,n", [(0, 40), (3, 40), (17, 200), (40, 40)])
def test_clopper_pearson_bounds_solve_the_binomial_tails(k, n):
    """lo: P(B >= k | lo) = 0.025; hi: P(B <= k | hi) = 0.025 (the defining equations)."""
    lo, hi = stats.clopper_pearson(k, n)
    if k == 0:
        assert lo == 0.0
    else:
        tail = 1 - sum(math.comb(n, i) * lo ** i * (1 - lo) ** (n - i) for i in range(k))
        assert tail == pytest.approx(0.025, abs=1e-9)
    if k == n:
        assert hi == 1.0
    else:
        cdf = sum(math.comb(n, i) * hi ** i * (1 - hi) ** (n - i) for i in range(k + 1))
        assert cdf == pytest.approx(0.025, abs=1e-9)


def ranks(v):
    """Average ranks (ties shared), written out."""
    order = sorted(range(len(v)), key=lambda i: v[i])
    r = [0.0] * len(v)
    i = 0
    while i < len(v):
        j = i
        while j + 1 < len(v) and v[order[j + 1]] == v[order[i]]:
            j += 1
        for t in range(i, j + 1):
            r[order[t]] = (i + j) / 2 + 1
        i = j + 1
    return np.array(r)


def test_spearman_table_is_pearson_of_ranks():
    rng = np.random.default_rng(7)
    y = rng.normal(size=200)
    cols = [y + rng.normal(size=200), np.round(rng.normal(size=200), 1), -y ** 3, rng.normal(size=200)]
    cols[3][5:9] = np.nan    # a column with NaN inside y's runs: the one-by-one path
    got = stats.spearman_table(cols, y, {})
    for x, (rho, n) in zip(cols, got):
        m = np.isfinite(x) & np.isfinite(y)
        want = np.corrcoef(ranks(list(x[m])), ranks(list(y[m])))[0, 1]
        assert n == int(m.sum()) and rho == pytest.approx(want, abs=1e-12)
    assert got[2][0] == pytest.approx(-1.0, abs=1e-15)


def test_spearman_undefined_for_a_constant_or_too_few():
    assert math.isnan(stats.spearman(np.ones(10), np.arange(10.0))[0])
    assert math.isnan(stats.spearman(np.arange(2.0), np.arange(2.0))[0])


def test_stats_comparison_counts_orders_and_moments_apart():
    c = stats.StatsComparison()
    c.add({"count": 5, "mean": 1.0, "min": 0.0}, {"count": 5, "mean": 1.0 + 2e-12, "min": 0.5}, 10.0,
          ["count", "mean", "min"])
    assert c.count_mismatches == 0 and c.order == pytest.approx(0.05) and c.moments == pytest.approx(2e-13)
    c.add({"count": 4}, {"count": 5}, 1.0, ["count"])
    assert c.count_mismatches == 1
    assert stats.scaled_diff(float("nan"), 1.0, 1.0) == float("inf")
    assert stats.scaled_diff(float("nan"), float("nan"), 1.0) == 0.0


def test_lock_order_and_intervals():
    top_first = np.array([[3.0, 2.0, 1.0], [3.5, 2.5, 1.0]])
    assert stats.lock_order(top_first) == "descending"
    dt, _ = stats.lock_intervals(top_first, "descending")
    assert np.array_equal(dt[:, :2], [[1.0, 1.0], [1.0, 1.5]]) and np.all(np.isnan(dt[:, 2]))
    assert stats.lock_order(top_first[:, ::-1]) == "ascending"
    assert stats.lock_order(np.array([[1.0, 2.0, 1.5]])) == "mixed"


def test_column_stats_fields():
    x = np.array([1.0, 2.0, 4.0, 8.0])
    s = stats.column_stats(x)
    assert s["count"] == 4 and s["mean"] == 3.75 and s["min"] == 1.0 and s["max"] == 8.0
    assert s["std"] == pytest.approx(math.sqrt(sum((v - 3.75) ** 2 for v in x) / 3), rel=1e-15)
    assert math.isnan(stats.column_stats(np.array([]))["mean"])
