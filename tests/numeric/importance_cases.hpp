// importance_cases.hpp — analytic cases for cross-entropy importance sampling and reweighting
// (src/sampling/importance_sampling.hpp, reweighting.hpp), driven as the engine would drive them:
// each round's plan through its bytes, each point from the decoded plan and its index.
//
// The cases sweep one distribution: dimension 0 (or every dimension) of the standard normal space is
// the draw x of a normal dispersion, the campaign's own law N(0, 1), and a design value v changes its
// law to N(m_v, s_v^2) (a nominal: m_v; a spread: s_v). The margin is a linear limit state in the
// draws, so each value's p is exact:
//   one      g = beta - x_0                           (the other dimensions do not matter):
//            p_v = Phi(-(beta - m_v) / s_v);
//   all      g = beta - sum_j x_j / sqrt(d), every dimension the same law (a per-bay dispersion):
//            p_v = Phi(-(beta - sqrt(d) m_v) / s_v).
#pragma once
#include <cmath>
#include <span>
#include <vector>

#include "sampling/importance_sampling.hpp"
#include "sampling/law_mixture.hpp"
#include "sampling/reweighting.hpp"
#include "sampling/sampling.hpp"

namespace truss::testing {

struct SweptLaw {
  double mean = 0.0, std = 1.0;
};

struct SweepCase {
  double beta = 4.0;
  bool all_dims = false;  // the law applies to every dimension, else to dimension 0 only
  double calc_margin(const double* z, int d) const {
    if (!all_dims) return beta - z[0];
    double s = 0.0;
    for (int j = 0; j < d; ++j) s += z[j];
    return beta - s / std::sqrt(static_cast<double>(d));
  }
  double calc_exact_p(const SweptLaw& v, int d) const {
    const double m = all_dims ? std::sqrt(static_cast<double>(d)) * v.mean : v.mean;
    return 0.5 * std::erfc((beta - m) / v.std / std::sqrt(2.0));
  }
  // ln f_v(z) - ln phi(z) over the swept dimensions (reweighting.hpp's DrawLaw ratio).
  double calc_log_ratio(const double* z, int d, const SweptLaw& v) const {
    const sampling::DrawLaw base{sampling::Distribution::normal(0.0, 1.0)};
    const sampling::DrawLaw target{sampling::Distribution::normal(v.mean, v.std)};
    double r = 0.0;
    for (int j = 0; j < (all_dims ? d : 1); ++j) r += sampling::calc_log_ratio(base, target, z[j]);
    return r;
  }
};

// The engine's block of the swept dimensions for these laws (law_mixture.hpp), the base N(0, 1).
inline sampling::SweptBlock make_swept_block(const SweepCase& c, const std::vector<SweptLaw>& laws, int d) {
  sampling::SweptBlock b;
  b.offset = 0;
  b.count = c.all_dims ? d : 1;
  b.base = {sampling::Distribution::normal(0.0, 1.0)};
  for (const SweptLaw& v : laws) b.laws.push_back({sampling::Distribution::normal(v.mean, v.std)});
  return b;
}

// Runs the sampler to its end; the cross-entropy levels adapt to the mixture of the laws `adapt`
// (empty: the campaign's own law); the final round's deviation density g (nullptr: N(0, I)).
inline sampling::CrossEntropySampler run_importance(const sampling::ImportanceOptions& o, const SweepCase& c,
                                                    const std::vector<SweptLaw>& adapt = {},
                                                    const sampling::Deviation* g = nullptr) {
  sampling::CrossEntropySampler s(o);
  std::vector<double> z(static_cast<std::size_t>(o.dims)), margins, ratio;
  while (!s.done()) {
    const sampling::ImportanceRound r = sampling::ImportanceRound::decode(s.round().encode(), o.dims);
    margins.resize(static_cast<std::size_t>(r.n_points));
    ratio.assign(adapt.empty() ? 0 : margins.size(), 0.0);
    for (std::int64_t k = 0; k < r.n_points; ++k) {
      sampling::calc_round_normals(o, r, k, z.data(), g);
      margins[static_cast<std::size_t>(k)] = c.calc_margin(z.data(), o.dims);
      if (adapt.empty()) continue;
      double mix = 0.0;  // ln of the mixture's mean ratio
      for (const SweptLaw& v : adapt) mix += std::exp(c.calc_log_ratio(z.data(), o.dims, v));
      ratio[static_cast<std::size_t>(k)] = std::log(mix / static_cast<double>(adapt.size()));
    }
    s.add_margins(margins, ratio);
  }
  return s;
}

// The estimate for law v from the sampler's final runs.
inline sampling::WeightedEstimate calc_swept_estimate(const sampling::CrossEntropySampler& s, const SweepCase& c,
                                                      const SweptLaw& v, const sampling::Deviation* g = nullptr) {
  const sampling::ImportanceOptions& o = s.options();
  std::vector<double> log_w = s.calc_final_log_weights(g), z(static_cast<std::size_t>(o.dims));
  for (std::size_t k = 0; k < log_w.size(); ++k) {
    sampling::calc_round_normals(o, s.final_round(), static_cast<std::int64_t>(k), z.data(), g);
    log_w[k] += c.calc_log_ratio(z.data(), o.dims, v);
  }
  return sampling::calc_weighted_estimate(s.final_margins(), log_w, 0.95);
}

}  // namespace truss::testing
