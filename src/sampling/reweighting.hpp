// reweighting.hpp — one set of runs serving several input distributions by likelihood ratios, and
// the estimate of a failure probability from weighted runs, refused where the weights degenerate.
// Pure functions; no I/O.
//
// Runs drawn from a sampling density q estimate P_f(fail) under any law f whose support lies in q's:
// p^_f = (1/n) sum_i 1{fail_i} w_i, w_i = f(x_i) / q(x_i) (importance sampling; R. Y. Rubinstein,
// D. P. Kroese, "Simulation and the Monte Carlo method", 3rd ed., Wiley 2017, ch. 5). A campaign's
// run is a point z of the standard normal space mapped dimension by dimension to draws
// x_j = F_j^-1(Phi(z_j)); with z drawn from h, q(x) / f_0(x) = h(z) / phi(z), so for a target law
// f that differs from the campaign's f_0 in some dimensions:
//   ln w = ln phi(z) - ln h(z) + sum_j [ln f_j'(x_j) - ln f_j(x_j)]   (j over the changed dimensions).
// A design value that changes only a distribution (a dispersion's spread, or the nominal of a
// dispersed key) is such an f: the same runs serve it.
//
// A target draw's law (DrawLaw): the draw in the base's coordinate is scale X + shift, X ~ dist. A
// spread sweep changes dist (scale 1, shift 0). A nominal sweep of a key dispersed with
// apply = "offset" (scene value n + d) moves the draw: shift = n_v - n_0; with apply = "relative"
// (n (1 + d)): scale = n_v / n_0, shift = n_v / n_0 - 1.
//
// The estimate (calc_weighted_estimate): p^ as above; its CoV from the sample variance of
// 1{fail} w, sqrt(var / n) / p^; the effective sample size of the failing runs (L. Kish, "Survey
// sampling", Wiley 1965): ESS = (sum_fail w)^2 / sum_fail w^2, the number of equally weighted
// failing runs the estimate is worth; the Pareto k of their weights (calc_pareto_k), the weight of
// its tail. The interval: lognormal with the CoV (allowable.hpp), as the other estimators of the
// sweeps. Refused (no estimate, the reason said) with no failing run, an ESS below kMinEss or a k
// above kMaxParetoK: the sample variance then rests on a few runs whose weights dominate, and the
// interval does not hold its confidence. A weighted estimate cannot see the failures its runs did
// not reach: where the density misses part of the failure region every diagnostic of the runs
// looks fine and the estimate is low; the density's own refusal (importance_sampling.hpp) and the
// coverage studies (bench/importance_coverage.py, docs/benchmarks.md) are the guard there.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "sampling/allowable.hpp"
#include "sampling/sampling.hpp"

namespace truss::sampling {

struct DrawLaw {
  Distribution dist;
  double scale = 1.0, shift = 0.0;
  // ln density of the draw d: ln f_X((d - shift) / scale) - ln |scale|; -inf outside the support.
  double calc_log_density(double d) const;
  std::string validate() const;  // "" when usable: dist valid, scale > 0, both finite
};

// Why draws of `base` cannot be reweighted to `target` ("" when they can): a discrete law (no
// density: only its own draws), or a target that puts probability where the base draws none (its
// support not inside the base's: the runs never see that part).
std::string find_reweighting_refusal(const DrawLaw& base, const DrawLaw& target);

// ln f_target(d) - ln f_base(d) for a draw d of base.
inline double calc_log_ratio(const DrawLaw& base, const DrawLaw& target, double d) {
  return target.calc_log_density(d) - base.calc_log_density(d);
}

inline constexpr double kMinEss = 30.0, kMaxParetoK = 0.7;

struct WeightedEstimate {
  double p = std::numeric_limits<double>::quiet_NaN();
  double cov = std::numeric_limits<double>::quiet_NaN();
  double ess = 0.0;                 // effective sample size of the failing runs
  double pareto_k = std::numeric_limits<double>::quiet_NaN();  // tail shape of their weights (see above)
  std::int64_t runs = 0, failures = 0, unusable = 0;
  ProbabilityBounds bounds;         // NaN when refused
  std::string refused;              // "" when the estimate stands; else why not
};

// The shape k of a generalized Pareto distribution fitted to the largest M = min(S / 5, 3 sqrt(S))
// of S weights over the next one (J. Zhang, M. A. Stephens, "A new and efficient estimation method
// for the generalized Pareto distribution", Technometrics 51 (2009) 316-325, with the weakly
// informative prior of A. Vehtari, D. Simpson, A. Gelman, Y. Yao, J. Gabry, "Pareto smoothed
// importance sampling", JMLR 25 (2024) 1-58): the weights' variance is finite for k < 1/2, and an
// estimate from S runs is reliable for k below about 0.7. NaN with fewer than 5 weights; -inf when
// the largest are equal (no tail).
double calc_pareto_k(std::vector<double> w);

// margins[i] <= 0 fails (NaN: the run cannot say; counts as safe, and as unusable); log_w[i] the
// run's ln w. Every field is filled also when refused (for the studies), bounds only when not.
WeightedEstimate calc_weighted_estimate(std::span<const double> margins, std::span<const double> log_w,
                                        double confidence);

}  // namespace truss::sampling
