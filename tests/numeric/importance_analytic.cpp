// importance_analytic — cross-entropy importance sampling on a swept analytic case
// (importance_cases.hpp): one JSON object per seed with, per swept law, the estimate, its CoV, its
// effective sample size, whether it was refused, and the exact p. For bench/importance_coverage.py.
//   importance_analytic --beta B [--all-dims] [--dims D] [--n N] [--n-final M] 
//                       [--means m1 m2 ...] [--stds s1 s2 ...] [--adapt-mixture] [--final-mixture] [--seed S] [--seeds K]
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "numeric/importance_cases.hpp"

int main(int argc, char** argv) {
  CLI::App app{"cross-entropy importance sampling on a swept analytic case"};
  truss::testing::SweepCase c;
  truss::sampling::ImportanceOptions o;
  o.dims = 10;
  std::vector<double> means{0.0}, stds{1.0};
  bool mixture = false;
  std::uint64_t seeds = 1;
  app.add_option("--beta", c.beta, "the limit state's beta");
  app.add_flag("--all-dims", c.all_dims, "the law applies to every dimension (else to dimension 0)");
  app.add_option("--dims", o.dims);
  app.add_option("--n", o.n_per_level, "points of a cross-entropy level");
  app.add_option("--n-final", o.n_final, "points of the final round");
  app.add_option("--rho", o.rho);
  app.add_option("--means", means, "the swept laws' means (one, or one per std)");
  app.add_option("--stds", stds, "the swept laws' standard deviations");
  app.add_flag("--adapt-mixture", mixture, "adapt to the mixture of the swept laws (else to N(0, 1))");
  bool final_mixture = false;
  app.add_flag("--final-mixture", final_mixture,
               "draw the final runs from the swept laws' mixture at the mean (law_mixture.hpp; else N(mu, I))");
  app.add_option("--seed", o.seed);
  app.add_option("--seeds", seeds);
  CLI11_PARSE(app, argc, argv);
  if (means.size() == 1) means.resize(stds.size(), means[0]);
  if (stds.size() == 1) stds.resize(means.size(), stds[0]);
  std::vector<truss::testing::SweptLaw> laws;
  for (std::size_t i = 0; i < stds.size(); ++i) laws.push_back({means[i], stds[i]});
  if (const std::string why = o.validate(); !why.empty() || means.size() != stds.size()) {
    std::fprintf(stderr, "importance_analytic: %s\n", why.empty() ? "--means and --stds differ in length" : why.c_str());
    return 2;
  }
  const truss::sampling::SweptBlock block = truss::testing::make_swept_block(c, laws, o.dims);
  const truss::sampling::LawMixture law_mixture(block, o.dims);
  const truss::sampling::Deviation* g = final_mixture ? &law_mixture : nullptr;
  const std::uint64_t first = o.seed;
  for (std::uint64_t s = first; s < first + seeds; ++s) {
    o.seed = s;
    const auto sampler = truss::testing::run_importance(o, c, mixture ? laws : std::vector<truss::testing::SweptLaw>{}, g);
    std::string out;
    for (const auto& v : laws) {
      const auto e = truss::testing::calc_swept_estimate(sampler, c, v, g);
      out += fmt::format("{}{{\"mean\": {}, \"std\": {}, \"exact_p\": {:.17g}, \"p\": {:.17g}, \"cov\": {:.17g}, "
                         "\"ess\": {:.17g}, \"pareto_k\": {:.17g}, \"failures\": {}, \"refused\": {}}}", out.empty() ? "" : ", ", v.mean,
                         v.std, c.calc_exact_p(v, o.dims), e.p, std::isfinite(e.cov) ? e.cov : -1.0, e.ess,
                         std::isfinite(e.pareto_k) ? e.pareto_k : 99.0, e.failures,
                         e.refused.empty() && sampler.find_refusal().empty() ? "false" : "true");
    }
    fmt::print("{{\"seed\": {}, \"status\": \"{}\", \"levels\": {}, \"runs\": {}, \"mean_noise\": {:.17g}, "
               "\"laws\": [{}]}}\n", s, to_string(sampler.status()), sampler.levels().size(), sampler.runs(),
               sampler.levels().back().mean_noise, out);
  }
  return 0;
}
