// law_mixture.hpp — the laws a sweep's values give a block of sampling dimensions, and the final
// density of a reweighted spread sweep: the mixture of those laws, each carried to the importance
// density's mean. Pure functions; no I/O.
//
// The block: dimensions [offset, offset + count) of the standard normal space whose draws
// d_j = F_b^-1(Phi(z_j)) have the base law b in the runs and law k (reweighting.hpp: DrawLaw) at
// value k of the sweep; R_k(z) = sum_j [ln f_k(d_j) - ln f_b(d_j)] (calc_log_ratios), so law k's
// density in the normal space is phi(z) exp(R_k(z)).
//
// The mixture (LawMixture, a Deviation of importance_sampling.hpp): with the cross-entropy mean mu,
// a single final density N(mu, I) serves a narrower law k through weights f_k / h whose spread grows
// with the number of swept dimensions and the laws' ratio of scales (ten dimensions at 0.74 of the
// base: an ESS of 73 of 2,000 runs). Component k carries law k's draws to the mean,
//   h_k(z) = g_k(z - mu),  g_k(n) = phi(n) exp(R_k(n)):
// n_j = Phi^-1(F_b(F_k^-1(Phi(e_j)))) in the block (a draw of law k, read in the base's normal
// space), n_j = e_j elsewhere, e the point's keyed normals; for normal laws N(m, s_k) against
// N(m, s_b) that is n_j = (s_k / s_b) e_j. The final density is q = (1/K) sum_k h_k, the component
// of a point chosen by its own keyed uniform (so the runs are independent draws of q and the sample
// variance of the weighted estimate holds), and every law's weight f_k / q <= K f_k / h_k is bounded
// as by a density of its own spread (the balance heuristic: E. Veach, L. J. Guibas, "Optimally
// combining sampling techniques for Monte Carlo rendering", SIGGRAPH 1995; T. Hesterberg, "Weighted
// average importance sampling and defensive mixture distributions", Technometrics 37 (1995)
// 185-194). The base law is one of the components, so q covers every point N(mu, I) covers.
// Only for a spread sweep: values that shift a law (a nominal sweep) fail in the same place of the
// normal space, which one mean serves; carrying each to the mean would move it off the failures.
#pragma once

#include <span>
#include <vector>

#include "sampling/importance_sampling.hpp"
#include "sampling/reweighting.hpp"

namespace truss::sampling {

struct SweptBlock {
  int offset = 0, count = 0;
  DrawLaw base;               // the runs' law of each draw (scale 1, shift 0)
  std::vector<DrawLaw> laws;  // one per value
  // R_k at the uniforms u = Phi(z) of a point (all its dims), for each value k, into out (laws.size()).
  void calc_log_ratios(const double* u, std::span<double> out) const;
  // ln (1/K) sum_k exp(R_k): the ratio of the laws' equal mixture to the base at u.
  double calc_log_mixture_ratio(const double* u) const;
};

class LawMixture final : public Deviation {
 public:
  // `block` must outlive the mixture; dims: the points' dimensions.
  LawMixture(const SweptBlock& block, int dims) : block_(block), dims_(dims) {}
  void transport(double pick, double* n) const override;
  double calc_log_ratio(const double* n) const override;  // ln (1/K) sum_k exp(R_k(n))
  std::size_t find_component(double pick) const;         // the component a point's pick chooses

 private:
  const SweptBlock& block_;
  int dims_ = 0;
};

}  // namespace truss::sampling
