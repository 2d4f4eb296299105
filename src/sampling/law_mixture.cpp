// law_mixture.cpp — the swept laws' ratios and their mixture at the importance density's mean
// (law_mixture.hpp).
#include "sampling/law_mixture.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sampling/sampling.hpp"

namespace truss::sampling {

void SweptBlock::calc_log_ratios(const double* u, std::span<double> out) const {
  std::fill(out.begin(), out.end(), 0.0);
  for (int j = 0; j < count; ++j) {
    const double d = base.dist.calc_quantile(u[offset + j]);
    const double base_log = base.calc_log_density(d);
    for (std::size_t k = 0; k < laws.size(); ++k) out[k] += laws[k].calc_log_density(d) - base_log;
  }
}

double SweptBlock::calc_log_mixture_ratio(const double* u) const {
  std::vector<double> r(laws.size());
  calc_log_ratios(u, r);
  const double top = *std::max_element(r.begin(), r.end());
  if (!std::isfinite(top)) return top;
  double s = 0.0;
  for (double x : r) s += std::exp(x - top);
  return top + std::log(s / static_cast<double>(r.size()));
}

std::size_t LawMixture::find_component(double pick) const {
  const std::size_t K = block_.laws.size();
  return std::min(K - 1, static_cast<std::size_t>(pick * static_cast<double>(K)));
}

// A draw of law k (its quantile at Phi(e_j)), read back in the base's normal space.
void LawMixture::transport(double pick, double* n) const {
  const DrawLaw& law = block_.laws[find_component(pick)];
  for (int j = block_.offset; j < block_.offset + block_.count; ++j) {
    const double u = calc_open_normal_cdf(n[j]);
    n[j] = block_.base.dist.calc_normal_score(law.scale * law.dist.calc_quantile(u) + law.shift);
  }
}

double LawMixture::calc_log_ratio(const double* n) const {
  std::vector<double> u(static_cast<std::size_t>(dims_), 0.5);
  for (int j = block_.offset; j < block_.offset + block_.count; ++j)
    u[static_cast<std::size_t>(j)] = calc_open_normal_cdf(n[j]);
  return block_.calc_log_mixture_ratio(u.data());
}

}  // namespace truss::sampling
