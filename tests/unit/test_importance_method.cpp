// Cross-entropy importance sampling as a method of the engine (methods/importance_method.hpp) and as
// a sweep's reweighted inner method (methods/importance_sweep.hpp): the file's rules with file, key
// and line; the rounds driven here as the engine drives them (records in run-index order) on
// analytic limit states of the campaign's own uniforms, whose failure probabilities are known
// exactly: g = beta - (z1 + z2) / sqrt(2) (p = Phi(-beta)), and for a spread sweep g = a - d, d the
// swept normal draw of std s (p = Phi(-a / s) at each value).
#include <catch2/catch.hpp>

#include <cmath>

#include <fmt/format.h>

#include "campaign/dispersion.hpp"
#include "campaign/evaluate.hpp"
#include "campaign_fixtures.hpp"
#include "methods/importance_method.hpp"
#include "methods/importance_sweep.hpp"
#include "methods/method_table.hpp"

using namespace truss;

namespace {

std::string ce_text(const std::string& ensemble_extra, const std::string& importance, const std::string& tail = "") {
  return fmt::format(R"([ensemble]
method = "importance"
master_seed = 5
{}
[ensemble.importance]
{}
[failure]
margin = "motor_torque_margin_Nm"
{}{}[[dispersion]]
key = "drive.speed_m_per_s"
distribution = "normal"
std = 0.05
)", ensemble_extra, importance, tail, campaign::test::kFourBaysStrutMass);
}

std::string error_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  return campaign::test::campaign_error(text, "ce.toml", sets);
}

// The engine's loop: propose, each run's uniforms, its margin, the next round; records in run order.
template <class MarginOf>
std::int64_t drive(methods::Method& m, int dims, MarginOf margin_of) {
  methods::RoundRecords prev;
  std::int64_t next = 0;
  std::vector<double> u(static_cast<std::size_t>(dims));
  for (std::int64_t round = 0;; ++round) {
    const methods::Proposal p = m.propose(round, prev);
    if (p.n_runs == 0) break;
    const methods::RoundPlan plan{round, next, p.n_runs, p.state};
    prev = {next, std::vector<std::int8_t>(static_cast<std::size_t>(p.n_runs), 0), {{}}};
    for (std::int64_t run = next; run < next + p.n_runs; ++run) {
      m.calc_uniforms(plan, run, u.data());
      prev.outputs[0].push_back(margin_of(u.data()));
    }
    next += p.n_runs;
  }
  return next;
}

}  // namespace

TEST_CASE("importance campaign keys: bad input named by file, key and line; the run cap as n_runs",
          "[methods][importance]") {
  // Lines: 1 [ensemble], 2 method, 3 master_seed, 4 extra, 5 [ensemble.importance], 6.. its keys.
  CHECK_THAT(error_of(ce_text("", "n_per_level = 100\nrho = 0.6")), Catch::Contains("ce.toml:7: ensemble.importance.rho"));
  CHECK_THAT(error_of(ce_text("", "n_final = 1")), Catch::Contains("ce.toml:6: ensemble.importance.n_final"));
  CHECK_THAT(error_of(ce_text("", "max_levels = 0")), Catch::Contains("ce.toml:6: ensemble.importance.max_levels"));
  CHECK_THAT(error_of(ce_text("", "n_per_level = 5\nrho = 0.1")), Catch::Contains("ensemble.importance.n_per_level"));
  CHECK_THAT(error_of(ce_text("", "rho = 0.1"), {"ensemble.importance.rho=0"}),
             Catch::Contains("--set ensemble.importance.rho=0: ensemble.importance.rho"));
  CHECK_THAT(error_of(ce_text("", "n_tail = 3")), Catch::Contains("ce.toml:6"));
  CHECK_THAT(error_of(ce_text("n_runs = 500", "rho = 0.1")), Catch::Contains("ce.toml:4: ensemble.n_runs"));
  CHECK_THAT(error_of(ce_text("sampling = \"lhs\"", "rho = 0.1")), Catch::Contains("ce.toml:4: ensemble.sampling"));
  const campaign::CampaignOptions o =
      methods::parse_campaign_text(ce_text("", "n_per_level = 300\nn_final = 700\nmax_levels = 5"), "ce.toml", ".");
  CHECK(o.ensemble.n_runs == 5 * 300 + 700);
}

// One seed: p within 3 of its own CoVs of the exact value (a two-sided 99.7 % check of an
// estimate whose log is close to normal at this ESS); the density reached the failure domain.
TEST_CASE("importance method: rounds whose points give the exact failure probability", "[methods][importance]") {
  const double beta = 4.0;  // p = 3.167e-5
  const campaign::CampaignContext ctx(methods::parse_campaign_text(
      ce_text("", "n_per_level = 500\nn_final = 1000"), "ce.toml", "."));
  REQUIRE(ctx.dims.total == 2);
  methods::ImportanceMethod m(ctx);
  const std::int64_t runs = drive(m, 2, [&](const double* u) {
    return beta - (sampling::normal_quantile(u[0]) + sampling::normal_quantile(u[1])) / std::sqrt(2.0);
  });
  const sampling::WeightedEstimate w = m.calc_estimate(0.95);
  const double exact = sampling::normal_cdf(-beta);
  INFO("p = " << w.p << " (exact " << exact << "), CoV " << w.cov << ", ESS " << w.ess << ", " << runs << " runs");
  // Adaptation on the margins of the wrong points (arrival order) never reaches the domain.
  CHECK(m.sampler().status() == sampling::ImportanceStatus::converged);
  CHECK(w.refused.empty());
  CHECK(m.sampler().runs() == runs);
  CHECK(std::abs(std::log(w.p / exact)) < 3.0 * w.cov);
  CHECK(w.cov < 0.1);  // the density at the design point: a tenth of crude Monte Carlo's 1/sqrt(n p) = 5.6
  CHECK(w.bounds.lower < exact);
  CHECK(w.bounds.upper > exact);
  const std::optional<methods::FailureEstimate> e = m.calc_failure_estimate(0.95);
  CHECK(e->bounds.p == w.p);
  CHECK(e->failures == -1);  // lognormal, not a count
  CHECK(e->untrusted.empty());
  CHECK(m.calc_result_failure().empty());
}

TEST_CASE("importance method: no failing final run is refused, with its reason", "[methods][importance]") {
  const campaign::CampaignContext ctx(
      methods::parse_campaign_text(ce_text("", "n_per_level = 100\nn_final = 200\nmax_levels = 2"), "ce.toml", "."));
  methods::ImportanceMethod m(ctx);
  drive(m, 2, [](const double* u) { return 50.0 - sampling::normal_quantile(u[0]); });  // p = Phi(-50)
  const std::optional<methods::FailureEstimate> e = m.calc_failure_estimate(0.95);
  CHECK_THAT(e->untrusted, Catch::Contains("refused: no failing run"));
  CHECK(std::isnan(e->bounds.upper_bound));
  CHECK_THAT(m.calc_result_failure(), Catch::Contains("no failing run"));
}

namespace {

std::string sweep_text(const std::string& sweep) {
  return fmt::format(R"([ensemble]
method = "importance"
master_seed = 7
[ensemble.importance]
n_per_level = 1000
n_final = 2000
[failure]
margin = "motor_torque_margin_Nm"
[sweep]
{}
target_probability = 1e-5
{}[[dispersion]]
key = "drive.speed_m_per_s"
distribution = "normal"
std = 0.05
)", sweep, campaign::test::kFourBaysStrutMass);
}

}  // namespace

// g = a - d with d the speed's offset draw: at std s, p = Phi(-a / s). One set of runs, drawn at the
// widest std, reweighted to each; a wrong likelihood ratio (the laws' ratio inverted, or left out)
// moves the narrow values' estimates by decades.
TEST_CASE("importance sweep: one set of runs reweighted to each spread gives each exact p", "[methods][importance]") {
  const double a = 0.2;
  const campaign::CampaignContext ctx(methods::parse_campaign_text(
      sweep_text("spread = \"drive.speed_m_per_s\"\nvalues = [0.036, 0.043, 0.05]"), "ce.toml", "."));
  std::unique_ptr<methods::Method> made = methods::builtin_methods().make(ctx);
  auto& m = dynamic_cast<methods::ImportanceSweepMethod&>(*made);
  const campaign::DimensionLayout& L = ctx.dims;
  const int speed = 1;  // the second dispersion's dimension (after the strut mass)
  const std::int64_t runs = drive(m, L.total, [&](const double* u) {
    CHECK(u[L.design] == Approx(2.5 / 3.0));  // every run at the widest value
    return a - 0.05 * sampling::normal_quantile(u[speed]);
  });
  const std::vector<methods::SweepMethod::ValueResult> vr = m.calc_value_results();
  REQUIRE(vr.size() == 3);
  for (const methods::SweepMethod::ValueResult& r : vr) {
    const double exact = sampling::normal_cdf(-a / r.value);
    INFO("std " << r.value << ": p = " << r.estimate.bounds.p << " (exact " << exact << "), CoV " << r.estimate.cov
                << ", " << r.estimate.message);
    CHECK(r.estimate.untrusted.empty());
    CHECK(r.estimate.runs == runs);
    CHECK(std::abs(std::log(r.estimate.bounds.p / exact)) < 3.0 * r.estimate.cov);
    CHECK(r.estimate.cov < 0.2);
  }
  // p rises with the spread: the allowable (upper bound 1e-5, exact crossing a / 4.265 = 0.0469) lies
  // between the last two values, the campaign's own 0.05 beyond it.
  const methods::SweepVerdict v = methods::calc_sweep_verdict(
      ctx.options, ctx.options.ensemble.method.as<methods::SweepOptions>(), vr);
  CHECK(v.verdict == "FAIL");
  CHECK(v.allowable.value > 0.043);
  CHECK(v.allowable.value < 0.05);
}

TEST_CASE("importance sweep: a nominal sweep of a relative draw reweights by its scale and shift",
          "[methods][importance]") {
  // g = c - x with x = nominal (1 + d), d ~ N(0, 0.05): p = Phi(-(c / nominal - 1) / 0.05).
  const double c = 0.012;
  const campaign::CampaignContext ctx(methods::parse_campaign_text(
      sweep_text("key = \"drive.speed_m_per_s\"\nvalues = [0.0095, 0.01, 0.0105]\nsafe_side = \"below\""), "ce.toml",
      "."));
  std::unique_ptr<methods::Method> made = methods::builtin_methods().make(ctx);
  auto& m = dynamic_cast<methods::ImportanceSweepMethod&>(*made);
  const campaign::DimensionLayout& L = ctx.dims;
  drive(m, L.total, [&](const double* u) {
    CHECK(u[L.design] == Approx(1.5 / 3.0));  // every run at the middle value, 0.01
    return c - 0.01 * (1.0 + 0.05 * sampling::normal_quantile(u[1]));
  });
  for (const methods::SweepMethod::ValueResult& r : m.calc_value_results()) {
    const double exact = sampling::normal_cdf(-(c / r.value - 1.0) / 0.05);
    INFO("nominal " << r.value << ": p = " << r.estimate.bounds.p << " (exact " << exact << "), CoV " << r.estimate.cov
                    << ", " << r.estimate.message);
    CHECK(r.estimate.untrusted.empty());
    CHECK(std::abs(std::log(r.estimate.bounds.p / exact)) < 3.0 * r.estimate.cov);
  }
}

TEST_CASE("importance sweep: a value that changes more than a distribution is refused at its line",
          "[methods][importance]") {
  // Lines: 9 [sweep], 10 its variable.
  CHECK_THAT(error_of(sweep_text("key = \"drive.stall_torque_Nm\"\nvalues = [0.02, 0.03]\nsafe_side = \"above\"")),
             Catch::Contains("ce.toml:10: sweep.key: \"drive.stall_torque_Nm\" is not dispersed"));
  CHECK_THAT(error_of(sweep_text("spread = \"drive.speed_m_per_s\"\nvalues = [0.03, 0.05]\nrefine = 2")),
             Catch::Contains("sweep.refine: the reweighted sweep"));
  CHECK(error_of(sweep_text("spread = \"drive.speed_m_per_s\"\nvalues = [0.03, 0.05]")).empty());
}
