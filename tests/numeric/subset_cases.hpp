// subset_cases.hpp — analytic limit states for the subset simulation tests, and a driver that runs
// the state machine as the evaluation engine would: each round's plan goes through its bytes
// (SubsetRound::encode / decode, as a broadcast would), and each point is computed from the
// decoded plan and its index, as its uniforms; the test evaluator maps them back to the standard
// normal space (as the dispersions' quantile functions would map them to inputs).
#pragma once
#include <cmath>
#include <vector>

#include "sampling/sampling.hpp"
#include "sampling/subset_simulation.hpp"

namespace truss::testing {

// Linear in Gaussian inputs: g(z) = beta - sum_j z_j / sqrt(d). The sum over sqrt(d) is standard
// normal, so P(g <= 0) = Phi(-beta) = erfc(beta / sqrt 2) / 2 exactly.
struct LinearCase {
  double beta;
  double calc_margin(const double* z, int d) const {
    double s = 0.0;
    for (int j = 0; j < d; ++j) s += z[j];
    return beta - s / std::sqrt(static_cast<double>(d));
  }
  double calc_exact_p(int /*d*/) const { return 0.5 * std::erfc(beta / std::sqrt(2.0)); }
};

// Outside a sphere (a failure domain no half-space describes): g(z) = r^2 - |z|^2. |z|^2 is
// chi-square with d degrees of freedom; for even d its survival function is the Poisson sum
// P(|z|^2 >= c) = e^(-c/2) sum_{k < d/2} (c/2)^k / k!.
struct SphereCase {
  double radius;
  double calc_margin(const double* z, int d) const {
    double s = 0.0;
    for (int j = 0; j < d; ++j) s += z[j] * z[j];
    return radius * radius - s;
  }
  double calc_exact_p(int d) const {
    const double x = 0.5 * radius * radius;
    double term = 1.0, sum = 0.0;
    for (int k = 0; k < d / 2; ++k) {
      sum += term;
      term *= x / (k + 1);
    }
    return std::exp(-x) * sum;
  }
};

template <class Case>
void drive_subset(sampling::SubsetSimulation& sim, const Case& c) {
  const sampling::SubsetOptions& o = sim.options();
  std::vector<double> u(static_cast<std::size_t>(o.dims)), margins;
  while (!sim.done()) {
    const sampling::SubsetRound r = sampling::SubsetRound::decode(sim.round().encode(), o.dims);
    margins.resize(static_cast<std::size_t>(r.n_points));
    for (std::int64_t k = 0; k < r.n_points; ++k) {
      sampling::calc_round_uniforms(o, r, k, u.data());
      for (double& x : u) x = sampling::normal_quantile(x);
      margins[static_cast<std::size_t>(k)] = c.calc_margin(u.data(), o.dims);
    }
    sim.add_margins(margins);
  }
}

template <class Case>
sampling::SubsetSummary run_subset(const sampling::SubsetOptions& o, const Case& c) {
  sampling::SubsetSimulation sim(o);
  drive_subset(sim, c);
  return sim.calc_summary();
}

}  // namespace truss::testing
