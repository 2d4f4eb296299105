// allowable.hpp — the allowable of a design sweep: from a failure probability estimated at each of
// several values of a design variable, the extreme value whose upper confidence bound on p stays at
// or below a target. Pure functions; no I/O.
//
// Bounds of one value's estimate, at confidence c:
//   subset simulation  lognormal: ln p^ ~ N(ln p, s^2), s^2 = ln(1 + cov^2) (the CoV of the
//                      estimator); one-sided upper bound p^ exp(z_c s); two-sided interval
//                      p^ exp(-+z_{(1+c)/2} s), z_q = Phi^-1(q).
//   Monte Carlo        k failures in n runs: Clopper-Pearson (stopping.hpp): the one-sided upper
//                      bound is the two-sided (2c - 1) interval's top (each tail 1 - c), the
//                      two-sided interval the exact one at c.
// The allowable, with the values x_1 < ... < x_m and their bounds:
//   safe side     where p falls: declared by the caller (a sweep's safe_side), never read from the
//                 estimates, whose ends are the noisiest (monotone_fit.hpp reads them through a
//                 monotone fit on that side).
//   allowable     from the safe end, the first value whose one-sided upper bound exceeds the target
//                 T and its safe neighbour (upper bound <= T) bracket it; between them the upper
//                 bound is interpolated linearly in ln p, and the allowable is where it equals T:
//                 x = x_a + (x_b - x_a) (ln T - ln u_a) / (ln u_b - ln u_a) (x_b itself when
//                 u_a = 0). So every value on the safe side of the allowable that was swept has its
//                 upper bound at or below T.
//   estimate      the same crossing of the estimates p^ (where p^ = T).
//   interval      the crossings of the two-sided interval's top and bottom: the design values
//                 between which the interval contains T; it contains the value where the true p
//                 equals T when the intervals of the two bracketing values hold the true p (each
//                 with probability c) and ln p is close to linear between them.
//   outside       no value's upper bound at or below T: the allowable lies beyond the safe end
//                 (extend the sweep that way); every value's at or below T: it lies beyond the
//                 other end (the sweep has not reached the target: extend it past that end). The
//                 ends are those of the values with an estimate. An interval end that lies
//                 outside the swept values is NaN.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace truss::sampling {

// One value's estimate and bounds; NaN bounds: the value has no usable estimate.
struct ProbabilityBounds {
  double p = std::numeric_limits<double>::quiet_NaN();
  double upper_bound = std::numeric_limits<double>::quiet_NaN();  // one-sided, confidence c
  double lower = std::numeric_limits<double>::quiet_NaN();        // two-sided interval at c
  double upper = std::numeric_limits<double>::quiet_NaN();
  bool usable() const { return upper_bound == upper_bound && lower == lower && upper == upper; }
};

// Subset simulation's estimate p with coefficient of variation cov (p <= 0 or a non-finite cov:
// unusable, NaN bounds).
ProbabilityBounds calc_lognormal_bounds(double p, double cov, double confidence);
// k failures in n runs.
ProbabilityBounds calc_binomial_bounds(std::int64_t k, std::int64_t n, double confidence);

// contradicts_safe_side: the estimates rise towards the declared safe side (monotone_fit.hpp).
enum class AllowableStatus { found, beyond_safe_end, beyond_unsafe_end, unusable, contradicts_safe_side };
inline constexpr const char* kAllowableStatusNames[] = {"found", "beyond_safe_end", "beyond_unsafe_end", "unusable",
                                                        "contradicts_safe_side"};
inline const char* to_string(AllowableStatus s) { return kAllowableStatusNames[static_cast<int>(s)]; }

struct Allowable {
  AllowableStatus status = AllowableStatus::unusable;
  int safe_side = 0;  // +1: p falls as the value grows (the allowable is a least value); -1: a greatest value
  double value = std::numeric_limits<double>::quiet_NaN();     // the crossing of the upper bound
  double estimate = std::numeric_limits<double>::quiet_NaN();  // the crossing of p^
  double lower = std::numeric_limits<double>::quiet_NaN();     // the interval, ascending (NaN: open)
  double upper = std::numeric_limits<double>::quiet_NaN();
  int bracket_safe = -1, bracket_unsafe = -1;  // the values bracketing `value` (indices), when found
  std::string message;  // one sentence: what was found, or which way to extend the sweep
};

// x ascending, one bounds per value; safe_side +1 or -1; target in (0, 1); units: x's unit, for the
// message: the walk from the safe end, the crossings and the messages above; `note` ends the message.
Allowable find_allowable_on_side(const std::vector<double>& x, const std::vector<ProbabilityBounds>& b,
                                 int safe_side, double target, const std::string& units = "",
                                 const std::string& note = "");

}  // namespace truss::sampling
