// monotone_fit.hpp — a sweep's allowable read through a monotone fit across all its values, with the
// safe side declared (never guessed from the estimates). Pure functions; no I/O.
//
// Each value's estimate is either lognormal (subset simulation, importance sampling: ln p^ ~
// N(ln p, s^2), s^2 = ln(1 + cov^2)) or binomial (Monte Carlo: k failures in n runs). An estimate
// flagged untrusted (a plateau of the margin, the level cap, no progress, weights that degenerate:
// SweepEstimate::untrusted says why) never enters the fit; neither does one without an estimate
// (p = 0 or no CoV for a lognormal estimate, no runs for a binomial one).
//
// The fit: isotonic regression (weighted pool-adjacent-violators; R. E. Barlow, D. J. Bartholomew,
// J. M. Bremner, H. D. Brunk, "Statistical inference under order restrictions", Wiley 1972) of p
// against the design value, non-increasing towards the safe side: a value whose estimate lies below
// that of a safer one is pooled with it into one block, as often as the order is violated. A
// lognormal block's estimate is the weighted mean of ln p^ with weights 1 / s^2 (the
// maximum-likelihood fit of ln p under the order); a binomial block's is its pooled share
// sum k / sum n (that of binomial proportions). Pooling corrects the order; it does not buy
// precision: each value keeps its own (the bounds of allowable.hpp around the block's estimate:
// lognormal with the value's own CoV; Clopper-Pearson of the value's own n runs with
// ceil(share n) failures). The values of a block need not share one p, and the precision of their
// pooled mean would hold for their average, not for the least safe of them: on log-linear p with
// s = 0.6, the pooled variance put the allowable on the unsafe side of the true crossing in 5.7 % of
// 4000 synthetic sweeps, each value's own in 3.7 % (the walk on the raw estimates: 3.2 %), while
// voiding half as many sweeps as the raw walk (tests/unit/test_monotone_fit.cpp).
//
// The allowable is then read from the fitted bounds as allowable.hpp reads it, on the declared side
// (find_allowable_on_side): from the safe end, the first value whose fitted upper bound exceeds the
// target and its safer neighbour bracket it, in ln p between them. Testing the values in a fixed
// order from the safe end, each at the confidence, and stopping at the first that fails, keeps the
// family-wise confidence without a correction for the number of values (a fixed-sequence test:
// W. Maurer, L. A. Hothorn, W. Lehmacher, "Multiple comparisons in drug clinical trials and
// preclinical assays: a-priori ordered hypotheses", in Biometrie in der chemisch-pharmazeutischen
// Industrie 6 (1995) 3-18); the order is only known when the safe side is.
//
// The declared side against the data: the weighted least-squares slope of ln p^ on x over the fitted
// values (binomial: ln((k + 1/2) / (n + 1/2)), variance 1 / (k + 1/2) - 1 / (n + 1/2)), in standard
// errors, signed positive when p falls towards the declared safe side (MonotoneFit::trend_z). When it
// is below -2.326 (p rises towards the declared safe side at the one-sided 1 % level) the fit refuses
// (status contradicts_safe_side) and says so: the declared side, or the margin, is wrong.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "sampling/allowable.hpp"

namespace truss::sampling {

enum class EstimateKind { lognormal, binomial };

// One design value's estimate of p.
struct SweepEstimate {
  double x = std::numeric_limits<double>::quiet_NaN();  // the design value
  EstimateKind kind = EstimateKind::lognormal;
  double p = std::numeric_limits<double>::quiet_NaN();    // lognormal: the estimate
  double cov = std::numeric_limits<double>::quiet_NaN();  // lognormal: its CoV
  std::int64_t failures = 0, runs = 0;                   // binomial
  std::string untrusted;  // non-empty: the estimate does not enter the fit, and this says why
};

struct MonotoneFit {
  Allowable allowable;                    // read from the fitted bounds (see above)
  std::vector<ProbabilityBounds> fitted;  // per value; NaN bounds where it did not enter the fit
  std::vector<int> block;                 // per value its block (0 at the safe end), -1 where not fitted
  std::vector<std::string> excluded;      // per value why it did not enter the fit ("" where it did)
  double trend_z = std::numeric_limits<double>::quiet_NaN();  // see above
};

// The z of the one-sided 1 % level below which the trend contradicts the declared side.
inline constexpr double kContradictingTrendZ = 2.3263478740408408;

// values: ascending in x, all of one kind; safe_side +1 (p falls as x grows: the allowable is a least
// value) or -1; target in (0, 1); confidence in (0, 1); units: x's unit, for the messages.
// Throws std::invalid_argument for values not ascending, of two kinds, or a bad side.
MonotoneFit calc_monotone_fit(const std::vector<SweepEstimate>& values, int safe_side, double target,
                              double confidence, const std::string& units = "");

}  // namespace truss::sampling
