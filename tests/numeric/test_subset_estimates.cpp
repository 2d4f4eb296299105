// test_subset_estimates.cpp — subset simulation's estimates against exact failure probabilities
// (subset_cases.hpp: linear limit states with p = Phi(-beta), the outside of a sphere with the
// chi-square law), over 20 master seeds each, driven as the evaluation engine would drive it.
//
// What a correct implementation gives, measured on 1000 seeds per case (d = 10, N = 2000,
// p0 = 0.1 unless said), and why each bound below is what it is:
//   * bias: +2 % (beta 3) to +5 % (beta 4.75) of p, O(1/N) as Au & Beck state (N = 500: +22 %,
//     N = 8000: +1.2 % at beta 4.75). Bound: the mean of 20 estimates within 3 of its standard
//     errors of the exact p (no group of 20 out of 150 exceeded 2.8).
//   * the CoV: Au & Beck's delta (SubsetSummary::cov) is 0.71-0.84 of the spread over seeds here,
//     and as little as 0.45 at p0 = 0.5 (it ignores the correlation between levels; OpenTURNS'
//     SubsetSampling shows the same: 0.25 against a spread of 0.34 at p = 1e-6). The ancestral
//     estimate (cov_lineage) is 0.93-1.0 of the spread of ln p^, so the test -- the
//     estimated CoV within a factor 1.5 of the spread over 20 seeds -- is asserted on it: it failed
//     in 0-2 % of 150 groups of 20 (Au & Beck's in 4-34 %). The spread is the standard deviation
//     of ln p^: for an estimator this skewed, a CoV is a statement about ln p^ to first order, and
//     the standard deviation of 20 values of p^ itself moves with its largest one.
//   * the estimates within 2 CoV of p (|ln p^ - ln p| <= 2 cov_lineage): 5.7-7.7 % of the runs fall
//     outside, 1.2-1.5 of 20; bound: at most 4 of 20 (P(>= 5) ~ 2 % at the worst rate).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "numeric/subset_cases.hpp"

using namespace truss::sampling;
using truss::testing::LinearCase;
using truss::testing::run_subset;
using truss::testing::SphereCase;

namespace {

constexpr int kSeeds = 20;

struct SeedStats {
  double exact = 0.0, mean = 0.0, se = 0.0, sd_log = 0.0;
  double cov_au_beck = 0.0, cov_lineage = 0.0;  // root mean squares over the seeds
  int outside = 0;                              // |ln p^ - ln p| > 2 cov_lineage
  std::int64_t max_runs = 0, max_lineages = 0, min_lineages = 0;
  double max_cov_au_beck = 0.0;
  bool all_converged = true;
};

template <class Case>
SeedStats run_seeds(const char* name, SubsetOptions o, const Case& c) {
  SeedStats st;
  st.exact = c.calc_exact_p(o.dims);
  std::vector<double> p, lp;
  double ab2 = 0.0, li2 = 0.0;
  st.min_lineages = o.n_per_level;
  for (int s = 1; s <= kSeeds; ++s) {
    o.seed = static_cast<std::uint64_t>(s);
    const SubsetSummary r = run_subset(o, c);
    st.all_converged = st.all_converged && r.status == SubsetStatus::converged && r.p > 0.0;
    p.push_back(r.p);
    lp.push_back(std::log(r.p));
    ab2 += r.cov * r.cov;
    li2 += r.cov_lineage * r.cov_lineage;
    st.outside += std::abs(std::log(r.p / st.exact)) > 2.0 * r.cov_lineage ? 1 : 0;
    st.max_runs = std::max(st.max_runs, r.runs);
    st.max_cov_au_beck = std::max(st.max_cov_au_beck, r.cov);
    st.min_lineages = std::min(st.min_lineages, r.lineages);
    st.max_lineages = std::max(st.max_lineages, r.lineages);
  }
  const auto sd = [](const std::vector<double>& x, double& mean) {
    mean = 0.0;
    for (double v : x) mean += v / static_cast<double>(x.size());
    double ss = 0.0;
    for (double v : x) ss += (v - mean) * (v - mean);
    return std::sqrt(ss / static_cast<double>(x.size() - 1));
  };
  double mean_log = 0.0;
  st.se = sd(p, st.mean) / std::sqrt(static_cast<double>(kSeeds));
  st.sd_log = sd(lp, mean_log);
  st.cov_au_beck = std::sqrt(ab2 / kSeeds);
  st.cov_lineage = std::sqrt(li2 / kSeeds);
  std::printf("%-26s exact %.4g mean %.4g (%+.1f %%, se %.1f %%) spread sd(ln p) %.3f | CoV Au-Beck %.3f (max %.3f) "
              "lineage %.3f | outside 2 CoV %d/%d | runs <= %lld | lineages %lld-%lld\n",
              name, st.exact, st.mean, 100.0 * (st.mean / st.exact - 1.0), 100.0 * st.se / st.exact, st.sd_log,
              st.cov_au_beck, st.max_cov_au_beck, st.cov_lineage, st.outside, kSeeds,
              static_cast<long long>(st.max_runs), static_cast<long long>(st.min_lineages),
              static_cast<long long>(st.max_lineages));
  return st;
}

void check_statistics(const SeedStats& st) {
  CHECK(st.all_converged);
  CHECK(std::abs(st.mean - st.exact) <= 3.0 * st.se);
  CHECK(st.outside <= 4);
  CHECK(st.cov_lineage >= st.sd_log / 1.5);
  CHECK(st.cov_lineage <= st.sd_log * 1.5);
}

SubsetOptions make_options(std::int64_t n, double p0) {
  SubsetOptions o;
  o.dims = 10;
  o.n_per_level = n;
  o.p0 = p0;
  return o;
}

}  // namespace

TEST_CASE("Subset simulation: linear limit state, beta = 3, 4, 4.75, 20 seeds", "[subset][estimates]") {
  for (double beta : {3.0, 4.0, 4.75}) {
    INFO("beta = " << beta);
    char name[64];
    std::snprintf(name, sizeof name, "linear beta %.2f", beta);
    const SeedStats st = run_seeds(name, make_options(2000, 0.1), LinearCase{beta});
    check_statistics(st);
  }
}

// p = 1e-6 within 12,000 evaluations: at N = 2000 a level boundary falls right at 1e-6 and half the
// seeds need a seventh level (12,800 runs), so N = 1800 (9,900 or 11,520 runs). Au & Beck's CoV
// is then 0.27-0.29 (<= 0.35, the target); the spread over 1000 seeds is 0.36 in ln p^
// (0.39 in p^), which the lineage estimate (0.34) tells and Au & Beck's does not.
TEST_CASE("Subset simulation: p = 1e-6 with at most 12,000 evaluations", "[subset][estimates]") {
  const double beta = -truss::sampling::normal_quantile(1e-6);
  const SeedStats st = run_seeds("linear p 1e-6 (N 1800)", make_options(1800, 0.1), LinearCase{beta});
  CHECK(st.max_runs <= 12000);
  CHECK(st.max_cov_au_beck <= 0.35);
  check_statistics(st);
}

TEST_CASE("Subset simulation: nonlinear failure domains and uneven chains", "[subset][estimates]") {
  // Outside the sphere |z| = 5.963 in 10 dimensions: p = 1.003e-4 (chi-square, 10 degrees).
  check_statistics(run_seeds("sphere r 5.963", make_options(2000, 0.1), SphereCase{5.963}));
  // p0 = 0.3, N = 1000: 300 chains, 100 of 4 states and 200 of 3 (Au & Beck's delta is 0.6 of the
  // spread here; the lineage estimate 0.99).
  check_statistics(run_seeds("linear beta 3, p0 0.3", make_options(1000, 0.3), LinearCase{3.0}));
}

// The interval a campaign reports (lognormal at 95 %, CoV = SubsetSummary::cov_bound) holds the
// exact p at least as often as its confidence, also where the failure samples descend from few
// roots: a limit state of two inputs at N = 500 (the lineage CoV's interval then held p in 78-84 %
// of 300 seeds, cov_bound's in 97-99 %) and ten inputs at N = 2000 (lineage 92-95 %, bound 100 %).
// Bound: the count of 300 seeds whose interval misses p is binomial; at a true coverage of 95 % it
// reaches 92 % (276 of 300) with probability 1.3 % (2.3 standard deviations), so 276 it is; the
// lineage CoV's interval fails this bound in both cases.
TEST_CASE("Subset simulation: the reported interval covers p at its confidence", "[subset][estimates]") {
  const double z95 = truss::sampling::normal_quantile(0.975);
  struct Case {
    int dims;
    std::int64_t n;
    double beta;
  };
  for (const Case c : {Case{2, 500, 4.7534}, Case{10, 2000, 4.7534}, Case{2, 500, 3.0902}}) {
    SubsetOptions o = make_options(c.n, 0.1);
    o.dims = c.dims;
    const LinearCase lc{c.beta};
    const double exact = lc.calc_exact_p(c.dims);
    int covered = 0, one_sided = 0;
    constexpr int kCoverageSeeds = 300;
    for (int s = 1; s <= kCoverageSeeds; ++s) {
      o.seed = static_cast<std::uint64_t>(1000 + s);
      const SubsetSummary r = run_subset(o, lc);
      REQUIRE(r.p > 0.0);
      CHECK(r.cov_bound >= r.cov_lineage);
      const double sd = std::sqrt(std::log1p(r.cov_bound * r.cov_bound)), e = std::log(r.p / exact);
      covered += std::abs(e) <= z95 * sd ? 1 : 0;
      one_sided += -e <= truss::sampling::normal_quantile(0.95) * sd ? 1 : 0;  // p <= the upper bound
    }
    std::printf("coverage d %d N %lld p %.3g: two-sided %d/%d, one-sided upper bound %d/%d\n", c.dims,
                static_cast<long long>(c.n), exact, covered, kCoverageSeeds, one_sided, kCoverageSeeds);
    INFO("d = " << c.dims << ", N = " << c.n << ", p = " << exact);
    CHECK(covered >= 276);
    CHECK(one_sided >= 276);
  }
}

// Adaptive conditional sampling (the proposal of Papaioannou et al. 2015): the same statistics on
// the linear case at p = 1e-6 and the sphere, and the interval CoV (cov_interval) against the
// bound: over 300 seeds its two-sided 95 % interval and its one-sided 95 % upper bound hold the
// exact p in at least 276 (the binomial bound above), and its median width on the log scale is at
// most 0.85 of cov_bound's (measured 0.62-0.75 on these cases, bench/subset_coverage.py).
TEST_CASE("Subset simulation, adaptive conditional sampling: estimates, interval coverage and width",
          "[subset][estimates][adaptive]") {
  SubsetOptions o = make_options(2000, 0.1);
  o.proposal = SubsetProposal::adaptive_conditional;
  check_statistics(run_seeds("aCS linear beta 4.75", o, LinearCase{4.75}));
  check_statistics(run_seeds("aCS sphere r 5.963", o, SphereCase{5.963}));
  const double z95 = truss::sampling::normal_quantile(0.975), z90 = truss::sampling::normal_quantile(0.95);
  struct Case {
    int dims;
    std::int64_t n;
    double beta;
  };
  for (const Case c : {Case{2, 500, 4.7534}, Case{10, 2000, 4.7534}, Case{2, 500, 3.0902}}) {
    o = make_options(c.n, 0.1);
    o.dims = c.dims;
    o.proposal = SubsetProposal::adaptive_conditional;
    const LinearCase lc{c.beta};
    const double exact = lc.calc_exact_p(c.dims);
    int covered = 0, one_sided = 0;
    std::vector<double> width, width_bound;
    constexpr int kCoverageSeeds = 300;
    for (int s = 1; s <= kCoverageSeeds; ++s) {
      o.seed = static_cast<std::uint64_t>(5000 + s);
      const SubsetSummary r = run_subset(o, lc);
      REQUIRE(r.p > 0.0);
      const double sd = std::sqrt(std::log1p(r.cov_interval * r.cov_interval)), e = std::log(r.p / exact);
      covered += std::abs(e) <= z95 * sd ? 1 : 0;
      one_sided += -e <= z90 * sd ? 1 : 0;
      width.push_back(sd);
      width_bound.push_back(std::sqrt(std::log1p(r.cov_bound * r.cov_bound)));
    }
    std::nth_element(width.begin(), width.begin() + kCoverageSeeds / 2, width.end());
    std::nth_element(width_bound.begin(), width_bound.begin() + kCoverageSeeds / 2, width_bound.end());
    const double ratio = width[kCoverageSeeds / 2] / width_bound[kCoverageSeeds / 2];
    std::printf("aCS coverage d %d N %lld p %.3g: two-sided %d/%d, one-sided %d/%d, median log-width against "
                "cov_bound's %.2f\n", c.dims, static_cast<long long>(c.n), exact, covered, kCoverageSeeds,
                one_sided, kCoverageSeeds, ratio);
    INFO("d = " << c.dims << ", N = " << c.n << ", p = " << exact);
    CHECK(covered >= 276);
    CHECK(one_sided >= 276);
    CHECK(ratio <= 0.85);
  }
}
