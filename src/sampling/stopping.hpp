// stopping.hpp — sequential stopping ([ensemble.stop]): run in rounds until a statistical target
// holds, with a cap on runs. Pure functions of the values so far; no I/O, no MPI.
//
// Targets:
//   probability_half_width           the half-width (hi - lo) / 2 of the Clopper-Pearson interval of
//   probability_relative_half_width  a failure probability k / n (absolute, or over k / n).
//   percentile_bound                 the one-sided distribution-free upper confidence bound of the
//                                    q-quantile exists and lies within a relative width of the
//                                    estimate: (bound - estimate) / |estimate| <= width.
//
// Why Clopper-Pearson and not Wilson: the report prints Clopper-Pearson intervals
// (postproc/truss_report/stats.py, clopper_pearson), so a campaign stopped here shows in its report
// an interval that meets the target it was stopped on; and the exact interval keeps its coverage
// (>= the confidence, for every p and n) where failures are rare, k = 0 to a few, which is the
// regime of a failure probability, while Wilson's coverage dips below the nominal level for
// n p of order 1 (L. D. Brown, T. T. Cai, A. DasGupta, "Interval estimation for a binomial
// proportion", Statistical Science 16 (2001) 101-133: Wilson's dips near p = 0). Its cost (an inverse incomplete
// beta function, Boost.Math) is nothing next to a run.
//
// The percentile bound is the report's (postproc/truss_report/design.py): from n sorted values,
// x_(k) with k the smallest rank such that F_Binomial(k - 1; n, q) >= confidence, for then
// P(x_(k) >= xi_q) = F_Binomial(k - 1; n, q) exactly (x_(k) >= xi_q holds when at most k - 1 values
// fall below xi_q, a Binomial(n, q) count, for a continuous distribution). No such k <= n exists
// when 1 - q^n < confidence: the smallest n with a bound is the least n with 1 - q^n >= confidence
// (2218 for q = 0.99865 at 95 %). The estimate is numpy's default percentile (Hyndman-Fan type 7).
//
// The next round: the width of either target shrinks as n^-1/2 (binomial standard deviation of
// k / n; for the quantile, the rank distance k - n q ~ z sqrt(n q (1 - q)) between the bound and the
// estimate, divided by n and by the density at xi_q), so the runs to reach a target width w from
// the current width w_n are about n (w_n / w)^2; the next total is that, kept between 1.25 n (a
// round worth having) and 4 n (the estimate of w_n is noisy), and never past max_runs. A
// percentile without a bound yet goes straight to the least n that has one.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>

namespace truss::sampling {

struct Interval {
  double lo = 0.0, hi = 1.0;
  double half_width() const { return 0.5 * (hi - lo); }
};

// Two-sided exact interval of a binomial proportion with k successes in n trials: each tail
// (1 - confidence) / 2; lo = 0 at k = 0, hi = 1 at k = n. Throws std::invalid_argument for
// k outside [0, n], n < 1, or confidence outside (0, 1).
Interval calc_clopper_pearson(std::int64_t k, std::int64_t n, double confidence);

// The smallest rank k in [1, n] with F_Binomial(k - 1; n, q) >= confidence, or 0 if none.
std::int64_t calc_upper_bound_rank(std::int64_t n, double q, double confidence);
// The least n with 1 - q^n >= confidence (the least n for which calc_upper_bound_rank is not 0).
std::int64_t calc_runs_for_upper_bound(double q, double confidence);
// Hyndman-Fan type 7 percentile of sorted values (q in [0, 1]); NaN when empty.
double calc_percentile_sorted(std::span<const double> sorted, double q);

enum class StopTarget { probability_half_width, probability_relative_half_width, percentile_bound };
inline constexpr const char* kStopTargetNames[] = {"probability_half_width", "probability_relative_half_width",
                                                   "percentile_bound"};
inline const char* to_string(StopTarget t) { return kStopTargetNames[static_cast<int>(t)]; }

struct StopRule {
  StopTarget target = StopTarget::percentile_bound;
  double confidence = 0.95;
  double width = 0.05;        // half-width (absolute), relative half-width, or relative width of the bound
  double level = 0.99865;     // percentile_bound: the quantile level q, in (0, 1)
  std::int64_t max_runs = 100000;

  // "" when usable, else "field: reason", including a rule that no outcome within max_runs can
  // meet (a percentile bound that needs more runs than max_runs; a half-width below the narrowest
  // interval max_runs can give, (1 - a^(1/n)) / 2 with a = (1 - confidence) / 2).
  std::string validate() const;
};

enum class StopState { met, more, capped };
inline constexpr const char* kStopStateNames[] = {"met", "more", "capped"};
inline const char* to_string(StopState s) { return kStopStateNames[static_cast<int>(s)]; }

struct StopDecision {
  StopState state = StopState::more;
  std::int64_t runs = 0;       // runs so far
  std::int64_t used = 0;       // values the statistic used (percentile: the finite ones)
  double estimate = std::numeric_limits<double>::quiet_NaN();  // k / n, or the percentile
  double lo = std::numeric_limits<double>::quiet_NaN();        // interval (probability)
  double hi = std::numeric_limits<double>::quiet_NaN();        // interval's top, or the upper bound
  std::int64_t bound_rank = 0;  // percentile: k of x_(k), 0 if none
  double achieved = std::numeric_limits<double>::infinity();  // the width in the rule's terms
  std::int64_t next_runs = 0;  // more runs for the next round (state == more)
  std::string reason;          // one sentence: why it stops or goes on
};

// Failure probability: `failures` of `runs` runs failed.
StopDecision decide_probability_stop(const StopRule& rule, std::int64_t failures, std::int64_t runs);
// Percentile: the output of every run so far (NaN or infinite: a run without a usable value,
// which counts as a run but not in the statistic).
StopDecision decide_percentile_stop(const StopRule& rule, std::span<const double> values);

}  // namespace truss::sampling
