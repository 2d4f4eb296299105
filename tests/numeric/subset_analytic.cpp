// subset_analytic — runs subset simulation on an analytic limit state (subset_cases.hpp) and prints
// one JSON object per seed: the estimate, its CoV, beta, runs, and per level the threshold, the
// conditional probability, gamma, acceptance and runs. For the OpenTURNS cross-check
// (test_subset_openturns.py) and for exploring N and p0 by hand.
//   subset_analytic --case linear|sphere --size BETA_OR_RADIUS [--dims D] [--n N] [--p0 P]
//                   [--seed S] [--seeds K]
#include <cstdio>
#include <map>
#include <string>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "numeric/subset_cases.hpp"

namespace {

template <class Case>
void print_run(const truss::sampling::SubsetOptions& o, const Case& c) {
  truss::sampling::SubsetSimulation sim(o);
  truss::testing::drive_subset(sim, c);
  const auto s = sim.calc_summary();
  std::string lags;
  for (int lag : {0, 1, 2, 3, -1}) lags += fmt::format("{}{:.17g}", lags.empty() ? "" : ", ", sim.calc_lag_cov(lag));
  std::string levels;
  for (const auto& l : s.levels)
    levels += fmt::format("{}{{\"threshold\": {:.17g}, \"probability\": {:.17g}, \"gamma\": {:.17g}, \"cov\": {:.17g}, "
                          "\"acceptance\": {:.17g}, \"scale\": {:.17g}, \"runs\": {}}}", levels.empty() ? "" : ", ",
                          l.threshold, l.probability, l.gamma, l.cov, std::isnan(l.acceptance()) ? -1.0 : l.acceptance(),
                          std::isnan(l.scale) ? -1.0 : l.scale, l.runs);
  fmt::print("{{\"seed\": {}, \"status\": \"{}\", \"p\": {:.17g}, \"cov\": {:.17g}, \"cov_lineage\": {:.17g}, "
             "\"cov_bound\": {:.17g}, \"lineages\": {}, \"lineage_groups\": {:.17g}, \"cov_interval\": {:.17g}, \"beta\": {:.17g}, \"runs\": {}, \"rounds\": {}, \"exact_p\": {:.17g}, "
             "\"cov_lag\": [{}], \"levels\": [{}]}}\n",
             o.seed, to_string(s.status), s.p, s.cov, s.cov_lineage, s.cov_bound, s.lineages, s.lineage_groups, s.cov_interval, s.beta, s.runs, s.rounds,
             c.calc_exact_p(o.dims), lags, levels);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"subset simulation on an analytic limit state"};
  std::string kind = "linear";
  double size = 3.0;
  truss::sampling::SubsetOptions o;
  o.dims = 10;
  std::uint64_t seeds = 1;
  app.add_option("--case", kind, "linear (size = beta) or sphere (size = radius)")
      ->check(CLI::IsMember({"linear", "sphere"}));
  app.add_option("--size", size, "beta of the linear case, radius of the sphere");
  app.add_option("--dims", o.dims, "standard normal dimensions");
  app.add_option("--n", o.n_per_level, "samples per level");
  app.add_option("--p0", o.p0, "conditional probability per level");
  app.add_option("--a", o.proposal_half_width, "half-width of the uniform proposal");
  app.add_option("--proposal", o.proposal, "modified_metropolis or adaptive_conditional")
      ->transform(CLI::CheckedTransformer(std::map<std::string, truss::sampling::SubsetProposal>{
          {"modified_metropolis", truss::sampling::SubsetProposal::modified_metropolis},
          {"adaptive_conditional", truss::sampling::SubsetProposal::adaptive_conditional}}));
  app.add_option("--seed", o.seed, "first master seed");
  app.add_option("--seeds", seeds, "number of consecutive seeds");
  CLI11_PARSE(app, argc, argv);
  if (const std::string why = o.validate(); !why.empty()) {
    std::fprintf(stderr, "subset_analytic: %s\n", why.c_str());
    return 2;
  }
  const std::uint64_t first = o.seed;
  for (std::uint64_t s = first; s < first + seeds; ++s) {
    o.seed = s;
    if (kind == "linear") print_run(o, truss::testing::LinearCase{size});
    else print_run(o, truss::testing::SphereCase{size});
  }
  return 0;
}
