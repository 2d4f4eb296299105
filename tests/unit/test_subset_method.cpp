// Subset simulation as a method of the engine (methods/subset_method.hpp) and its campaign keys
// (campaign_method.cpp): the file's rules with file, key and line; the method's rounds driven here
// as the engine drives them, on an analytic limit state of the campaign's own uniforms, whose
// failure probability is known exactly.
#include <catch2/catch.hpp>

#include <cmath>

#include <fmt/format.h>

#include "campaign/evaluate.hpp"
#include "campaign_fixtures.hpp"
#include "io/scene_toml.hpp"
#include "methods/method_table.hpp"
#include "methods/subset_method.hpp"

using namespace truss;

namespace {

std::string rare_text(const std::string& ensemble_extra, const std::string& subset, const std::string& failure) {
  return fmt::format(R"([ensemble]
method = "subset"
master_seed = 5
{}
[ensemble.subset]
{}
[failure]
{}
{}[[dispersion]]
key = "drive.speed_m_per_s"
distribution = "normal"
std = 0.05
)", ensemble_extra, subset, failure, campaign::test::kFourBaysStrutMass);
}

// The message of the error the text gives ("" if it parses).
std::string error_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  return campaign::test::campaign_error(text, "rare.toml", sets);
}

}  // namespace

TEST_CASE("subset campaign keys: bad input named by file, key and line; the run cap as n_runs", "[methods][subset]") {
  const std::string ok_subset = "n_per_level = 100\np0 = 0.1\nmax_levels = 4", margin = "margin = \"motor_torque_margin_Nm\"";
  // Lines: 1 [ensemble], 2 method, 3 master_seed, 4 extra, 5 [ensemble.subset], 6.. its keys.
  CHECK(error_of(rare_text("", "n_per_level = 100\np0 = 0.6", margin)).find("rare.toml:7: ensemble.subset.p0: 0.6") != std::string::npos);
  CHECK(error_of(rare_text("", "n_per_level = 100\np0 = 0.0", margin)).find("ensemble.subset.p0") != std::string::npos);
  CHECK(error_of(rare_text("", "n_per_level = 100\np0 = 0.125", margin)).find("whole number of chains") !=
        std::string::npos);
  CHECK(error_of(rare_text("", ok_subset, margin), {"ensemble.subset.p0=0.7"})
            .find("--set ensemble.subset.p0=0.7: ensemble.subset.p0") != std::string::npos);
  const std::string no_column = error_of(rare_text("", ok_subset, "margin = \"rail_margn_m\""));
  CHECK(no_column.find("rare.toml:10: failure.margin: \"rail_margn_m\" is not a float64 column") != std::string::npos);
  const std::string unit = error_of(rare_text("", ok_subset, "column = \"peak_drive_force_N\"\nabove = 3.5\nunit = \"kN\""));
  CHECK(unit.find("rare.toml:12: failure.unit: \"kN\", but peak_drive_force_N is in \"N\"") != std::string::npos);
  CHECK(error_of(rare_text("", ok_subset, "column = \"peak_drive_force_N\"\nabove = 3.5")).find("failure.unit: missing") !=
        std::string::npos);
  CHECK(error_of(rare_text("", ok_subset, "column = \"status\"\nabove = 3.5\nunit = \"1\""))
            .find("failure.column") != std::string::npos);
  CHECK(error_of(rare_text("n_runs = 500", ok_subset, margin)).find("rare.toml:4: ensemble.n_runs: method = \"subset\"") !=
        std::string::npos);
  std::string no_failure = rare_text("", ok_subset, "");
  no_failure.replace(no_failure.find("[failure]\n"), 10, "");
  CHECK(error_of(no_failure).find("failure: method = \"subset\" needs a [failure] table") != std::string::npos);
  CHECK(error_of(rare_text("", ok_subset, "")).find("rare.toml:9: failure: give either margin") != std::string::npos);
  std::string design = rare_text("", ok_subset, margin);
  design.replace(design.find("method = \"subset\""), 17, "method = \"design\"");
  design.replace(design.find("[ensemble.subset]\n" + ok_subset), 18 + ok_subset.size(), "");
  CHECK(error_of(design).empty());  // the design estimates the event's probability from its Monte Carlo runs
  // A margin the scene never computes (NaN in every run, so nothing ever fails): refused at its line.
  CHECK(error_of(rare_text("", ok_subset, "margin = \"rail_margin_m\"")).find(
            "rare.toml:10: failure.margin: \"rail_margin_m\" is defined only with stack.mode = \"free\" and "
            "run.direction = \"deploy\"") != std::string::npos);
  CHECK(error_of(rare_text("", ok_subset, margin), {"drive.mode=motor"})
            .find("rare.toml:10: failure.margin: \"motor_torque_margin_Nm\" is defined only with drive.mode = "
                  "\"velocity\"") != std::string::npos);
  // The stall torque that meets the motorisation factors needs a motor line: none in torque mode;
  // the motorisation margin itself is computed in every drive mode.
  const std::string stall = "column = \"motorisation_stall_torque_Nm\"\nbelow = 0.03\nunit = \"Nm\"";
  CHECK(error_of(rare_text("", ok_subset, stall)).empty());
  CHECK(error_of(rare_text("", ok_subset, stall), {"drive.mode=torque"})
            .find("rare.toml:10: failure.column: \"motorisation_stall_torque_Nm\" is defined only with drive.mode = "
                  "\"velocity\" or \"motor\"") != std::string::npos);
  CHECK(error_of(rare_text("", ok_subset, "margin = \"motorisation_margin\""), {"drive.mode=torque"}).empty());
  // A valid one: n_runs is the cap N + (max_levels - 1)(N - N_c); its resolved TOML reads back to it.
  const campaign::CampaignOptions o = methods::parse_campaign_text(rare_text("", ok_subset, margin), "rare.toml", ".");
  CHECK(o.ensemble.n_runs == 100 + 3 * 90);
  const campaign::CampaignOptions back =
      methods::parse_campaign_text(campaign::resolved_campaign_toml(o), "resolved.toml", ".");
  CHECK(back.ensemble.method.name() == "subset");
  CHECK(back.ensemble.n_runs == o.ensemble.n_runs);
  CHECK(back.ensemble.method.as<methods::SubsetMethodOptions>().subset.p0 == 0.1);
  CHECK(back.ensemble.method.as<methods::SubsetMethodOptions>().failure.kind == methods::FailureKind::margin);
  CHECK(back.ensemble.method.as<methods::SubsetMethodOptions>().failure.column == "motor_torque_margin_Nm");
}

TEST_CASE("subset campaign keys: the proposal and the interval's CoV, named values only", "[methods][subset]") {
  const std::string margin = "margin = \"motor_torque_margin_Nm\"", n = "n_per_level = 100\n";
  // Lines: 5 [ensemble.subset], 6 n_per_level, 7 the key under test.
  CHECK(error_of(rare_text("", n + "proposal = \"adaptive\"", margin))
            .find("rare.toml:7: ensemble.subset.proposal: \"adaptive\" is not one of \"modified_metropolis\", "
                  "\"adaptive_conditional\"") != std::string::npos);
  CHECK(error_of(rare_text("", n + "interval_cov = \"cov_lineage\"", margin))
            .find("rare.toml:7: ensemble.subset.interval_cov: \"cov_lineage\" is not one of \"cov_bound\", "
                  "\"cov_interval\"") != std::string::npos);
  CHECK(error_of(rare_text("", n, margin), {"ensemble.subset.proposal=mm"})
            .find("--set ensemble.subset.proposal=mm: ensemble.subset.proposal") != std::string::npos);
  // The uniform step's half-width belongs to modified Metropolis; aCS adapts its own spread.
  CHECK(error_of(rare_text("", n + "proposal = \"adaptive_conditional\"\nproposal_half_width = 0.5", margin))
            .find("rare.toml:8: ensemble.subset.proposal_half_width: the step of proposal = \"modified_metropolis\"") !=
        std::string::npos);
  CHECK(error_of(rare_text("", n + "proposal = \"modified_metropolis\"\nproposal_half_width = 0.5", margin)).empty());
  // Each choice reaches the state machine and the estimate, and the resolved TOML reads back to it.
  for (const char* proposal : sampling::kSubsetProposalNames)
    for (const char* rule : sampling::kSubsetIntervalCovNames) {
      INFO(proposal << " " << rule);
      const campaign::CampaignOptions o = methods::parse_campaign_text(
          rare_text("", n + fmt::format("proposal = \"{}\"\ninterval_cov = \"{}\"", proposal, rule), margin),
          "rare.toml", ".");
      const auto& m = o.ensemble.method.as<methods::SubsetMethodOptions>();
      CHECK(sampling::to_string(m.calc_sim_options(o).proposal) == std::string(proposal));
      CHECK(sampling::to_string(m.subset.interval_cov) == std::string(rule));
      const campaign::CampaignOptions back =
          methods::parse_campaign_text(campaign::resolved_campaign_toml(o), "resolved.toml", ".");
      const auto& b = back.ensemble.method.as<methods::SubsetMethodOptions>();
      CHECK(b.subset.proposal == m.subset.proposal);
      CHECK(b.subset.interval_cov == m.subset.interval_cov);
    }
}

TEST_CASE("subset campaign keys: a run cap past 64-bit counts is refused naming n_per_level", "[methods][subset]") {
  const std::string margin = "margin = \"motor_torque_margin_Nm\"";
  const std::string base = rare_text("", "n_per_level = 100\np0 = 0.1\nmax_levels = 3", margin);
  // N + (max_levels - 1)(N - N_c) at N = 2^63 - 1, p0 = 0.1: 2.9 N, past 2^63 (it wrapped to a
  // negative n_runs); at N = 2^62: 2.8 N, likewise; at N = 10^17 it fits 64 bits but not 2^53.
  for (const char* n : {"9223372036854775807", "4611686018427387904", "100000000000000000"}) {
    INFO(n);
    const std::string e = error_of(base, {fmt::format("ensemble.subset.n_per_level={}", n)});
    CHECK(e.find(fmt::format("ensemble.subset.n_per_level: {} samples per level over max_levels = 3 levels is more "
                             "than 2^53 runs", n)) != std::string::npos);
    CHECK(e.find("ensemble.n_runs") == std::string::npos);
  }
  // 2^53 / 2.8 rounded down to a multiple of 10 (whole chains) still fits: 3216855356317750 N.
  const campaign::CampaignOptions o =
      methods::parse_campaign_text(base, "rare.toml", ".", {"ensemble.subset.n_per_level=3216855356317750"});
  CHECK(o.ensemble.n_runs == 3216855356317750 + 2 * (3216855356317750 - 321685535631775));
}

TEST_CASE("subset method: margins from records; a failed run counts only when it shows the failure", "[methods][subset]") {
  methods::RoundRecords r;
  const auto ok = static_cast<std::int8_t>(sim::RunStatus::ok), miss = static_cast<std::int8_t>(sim::RunStatus::rail_miss),
             stall = static_cast<std::int8_t>(sim::RunStatus::stall);
  r.status = {ok, miss, stall, stall, ok};
  r.outputs = {{0.5, -0.2, 0.3, -0.1, std::nan("")}};
  methods::FailureOptions f;
  f.kind = methods::FailureKind::margin;
  std::vector<double> m = methods::FailureCount::calc_margins(f, r);
  CHECK(m[0] == 0.5);
  CHECK(m[1] == -0.2);
  CHECK(std::isnan(m[2]));  // a stall with a positive margin so far cannot say
  CHECK(m[3] == -0.1);      // it failed before it stalled
  CHECK(std::isnan(m[4]));
  f.kind = methods::FailureKind::above;
  f.threshold = 0.4;
  m = methods::FailureCount::calc_margins(f, r);
  CHECK(m[0] == Approx(-0.1));
  CHECK(std::isnan(m[1]));  // a rail miss whose column stays below the allowable: cannot say
  CHECK(std::isnan(m[2]));
  f.kind = methods::FailureKind::below;
  m = methods::FailureCount::calc_margins(f, r);
  CHECK(m[0] == Approx(0.1));
  CHECK(m[1] == Approx(-0.6));  // below the bound before the run stopped: a failure it shows
}

// The engine's loop, here: propose, the round's points by calc_uniforms, their margins, the next
// round. Limit state g = beta - (z1 + z2) / sqrt(2), z_j = Phi^-1(u_j): p = Phi(-beta) exactly.
TEST_CASE("subset method: rounds of contiguous runs whose points give the exact failure probability",
          "[methods][subset]") {
  const double beta = 3.5;  // p = 2.326e-4
  const campaign::CampaignContext ctx(methods::parse_campaign_text(
      rare_text("", "n_per_level = 1000\np0 = 0.1", "margin = \"motor_torque_margin_Nm\""), "rare.toml", "."));
  REQUIRE(ctx.dims.total == 2);
  methods::SubsetMethod m(ctx);
  auto margin_at = [&](const methods::RoundPlan& plan, std::int64_t run) {
    double u[2];
    m.calc_uniforms(plan, run, u);
    return beta - (sampling::normal_quantile(u[0]) + sampling::normal_quantile(u[1])) / std::sqrt(2.0);
  };
  std::vector<methods::RoundPlan> plans;
  methods::RoundRecords prev;
  std::int64_t next = 0;
  for (std::int64_t round = 0;; ++round) {
    methods::Proposal p = m.propose(round, prev);
    if (p.n_runs == 0) break;
    plans.push_back({round, next, p.n_runs, p.state});
    prev = {next, std::vector<std::int8_t>(static_cast<std::size_t>(p.n_runs), 0), {{}}};
    for (std::int64_t run = next; run < next + p.n_runs; ++run) prev.outputs[0].push_back(margin_at(plans.back(), run));
    next += p.n_runs;
  }
  const sampling::SubsetSummary s = m.simulation().calc_summary();
  const double exact = sampling::normal_cdf(-beta);
  INFO("p = " << s.p << " (exact " << exact << "), CoV " << s.cov_lineage << ", " << s.runs << " runs");
  CHECK(s.status == sampling::SubsetStatus::converged);
  CHECK(s.runs == next);
  CHECK(std::abs(std::log(s.p / exact)) < 3.0 * s.cov_lineage);  // one seed: within 3 CoV
  CHECK(s.levels.size() == 4);  // p0^3 = 1e-3 > p > p0^4
  // The failure samples name their runs: the point of that run in its round gives the margin.
  const std::vector<sampling::SubsetSample> fs = m.simulation().calc_failure_samples();
  REQUIRE(!fs.empty());
  for (const sampling::SubsetSample& x : fs) {
    CHECK(x.margin <= 0.0);
    const auto plan = std::find_if(plans.begin(), plans.end(), [&](const auto& p) { return p.contains(x.evaluation); });
    REQUIRE(plan != plans.end());
    CHECK(margin_at(*plan, x.evaluation) == x.margin);
  }
}

// The thresholds of a free-stack tolerance sweep's value at a diagonal-length std of 3.7 mm (its first
// seven moves are 0.1-0.22 % of the threshold, by hand) and of the rare-failure campaign (one such move).
TEST_CASE("subset method: plateau levels make the estimate untrusted from 3 on", "[methods][subset]") {
  auto levels = [](std::vector<double> b) {
    std::vector<sampling::SubsetLevel> l(b.size());
    for (std::size_t k = 0; k < b.size(); ++k) l[k].threshold = b[k];
    return l;
  };
  const auto flat = levels({0.10587291, 0.10564159, 0.1054759, 0.10535398, 0.10523497, 0.10512915, 0.10503073,
                            0.10491016, 0.06158238, 0.01592114, 0.0049516, 0.00155649, 0.0});
  const auto rare = levels({0.10584856, 0.10547424, 0.01141385, 0.00216291, 0.0});
  sampling::SubsetSummary s;
  s.status = sampling::SubsetStatus::converged;
  s.levels = rare;
  CHECK(s.calc_plateau_levels() == 1);
  s.levels = flat;
  CHECK(s.calc_plateau_levels() == 7);
  CHECK_THAT(methods::find_subset_distrust(s, 0, 1000), Catch::Contains("nearly flat over 7 levels"));
  s.levels = rare;
  CHECK(methods::find_subset_distrust(s, 10, 1000).empty());  // 1 %: stands
  CHECK_THAT(methods::find_subset_distrust(s, 11, 1000), Catch::Contains("11 of 1000 runs have no usable result"));
  s.status = sampling::SubsetStatus::no_progress;
  CHECK_THAT(methods::find_subset_distrust(s, 0, 1000), Catch::Contains("stopped decreasing"));
}
