// test_sweep.cpp — a design sweep's campaign side (campaign/design_axis.hpp): a run's design coordinate
// (k + 0.5) / n applies value k, to the base scene (a nominal sweep) or to the dispersion's spread,
// and the run's last input is that value; value k's standalone campaign and its seed; the resolved
// TOML reads back to the same sweep; the refinement's candidates (values by hand); the design and
// stop methods read [failure] (the event whose probability they estimate), and a sweep's run cap is
// its method's per value. Expected values by hand: an offset normal draw
// at u = Phi(1) is nominal + std (the normal quantile, exact to ~1e-16 relative).
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "campaign/campaign.hpp"
#include "campaign/design_axis.hpp"
#include "campaign/dispersion.hpp"
#include "campaign/failure.hpp"
#include "campaign/record.hpp"
#include "methods/method_table.hpp"
#include "methods/sweep_options.hpp"
#include "sampling/sampling.hpp"

using namespace truss::campaign;

namespace {

const char* kBase = R"(
[ensemble]
method = "subset"
master_seed = 5
[ensemble.subset]
n_per_level = 100
[failure]
margin = "motor_torque_margin_Nm"
[scene.drive]
stall_torque_Nm = 0.03
[[dispersion]]
key = "drive.stall_torque_Nm"
apply = "offset"
distribution = "normal"
std = 0.001
[[dispersion]]
key = "mast.strut_mass_kg"
per = "bay"
apply = "relative"
distribution = "normal"
std = 0.01
)";

const DesignAxis& axis(const CampaignOptions& c) { return *find_design_axis(c); }
const truss::methods::SweepOptions& sweep_of(const CampaignOptions& c) {
  return c.ensemble.method.as<truss::methods::SweepOptions>();
}

CampaignOptions parse(const std::string& sweep) {
  return truss::methods::parse_campaign_text(std::string(kBase) + sweep, "t", ".");
}

const double kPhi1 = 0.8413447460685429;  // Phi(1)

}  // namespace

TEST_CASE("a nominal sweep sets the key before the draws; the run records its value", "[sweep]") {
  const CampaignOptions c = parse("[sweep]\nkey = \"drive.stall_torque_Nm\"\nsafe_side = \"above\"\nvalues = [0.01, 0.02, 0.04]\n"
                                  "target_probability = 1e-6\n");
  const DimensionLayout L = calc_layout(c);
  REQUIRE(L.design == L.total - 1);
  REQUIRE(L.dispersion_dims() == 1 + L.n_bays_max);
  std::vector<double> u(static_cast<std::size_t>(L.total), 0.5);
  u[0] = kPhi1;
  for (std::size_t k = 0; k < 3; ++k) {
    u[static_cast<std::size_t>(L.design)] = (static_cast<double>(k) + 0.5) / 3.0;
    const RunInputs in = calc_run_inputs(c, L, u.data());
    const double want = axis(c).values[k] + 0.001;  // the swept nominal plus one std
    CHECK(in.scene.drive.stall_torque_Nm == Approx(want).epsilon(1e-12));
    CHECK(in.values[0][0] == Approx(want).epsilon(1e-12));
    CHECK(in.values.back() == std::vector<double>{axis(c).values[k]});
  }
  const RecordLayout R(c, L);
  CHECK(R.fields().back().name == "sweep_value");
  CHECK(R.fields().back().units == "Nm");
  CHECK(calc_sweep_own_value(c) == 0.03);
}

TEST_CASE("a spread sweep sets the dispersion's std at each value", "[sweep]") {
  const CampaignOptions c = parse("[sweep]\nspread = \"drive.stall_torque_Nm\"\nfrom = 0.001\nto = 0.003\n"
                                  "count = 3\ntarget_probability = 1e-6\n");
  CHECK(axis(c).values == std::vector<double>{0.001, 0.002, 0.003});
  CHECK(sweep_variable_name(c) == "drive.stall_torque_Nm std");
  const DimensionLayout L = calc_layout(c);
  std::vector<double> u(static_cast<std::size_t>(L.total), 0.5);
  u[0] = kPhi1;
  u[static_cast<std::size_t>(L.design)] = 2.5 / 3.0;
  CHECK(calc_run_inputs(c, L, u.data()).values[0][0] == Approx(0.03 + 0.003).epsilon(1e-12));
  // Value 1's standalone campaign: no sweep, std 0.002, the file's seed (common random numbers at
  // every value); the base scene untouched.
  const CampaignOptions at = calc_campaign_at(c, 1);
  CHECK(find_design_axis(at) == nullptr);
  CHECK(at.dispersions[0].std == 0.002);
  CHECK(at.base.drive.stall_torque_Nm == 0.03);
  CHECK(at.ensemble.master_seed == c.ensemble.master_seed);
  CHECK(calc_campaign_at(c, 2).ensemble.master_seed == c.ensemble.master_seed);
}

TEST_CASE("the resolved campaign reads back to the same sweep", "[sweep]") {
  const CampaignOptions c = parse("[sweep]\nkey = \"drive.stall_torque_Nm\"\nsafe_side = \"above\"\nfrom = 0.01\nto = 0.02\ncount = 4\n"
                                  "target_probability = 2e-5\nconfidence = 0.9\n");
  const CampaignOptions back = truss::methods::parse_campaign_text(resolved_campaign_toml(c), "resolved", ".");
  CHECK(axis(back).values == axis(c).values);
  CHECK(axis(back).key == axis(c).key);
  CHECK(sweep_of(back).target_probability == 2e-5);
  CHECK(sweep_of(back).confidence == 0.9);
  CHECK(sweep_of(back).calc_safe_side() == +1);
  CHECK(resolved_campaign_toml(back) == resolved_campaign_toml(c));
}

TEST_CASE("the safe side is declared or known, never guessed", "[sweep]") {
  // A key sweep without safe_side is refused where the key stands (file:line); a spread's is below.
  try {
    parse("[sweep]\nkey = \"drive.stall_torque_Nm\"\nvalues = [0.01, 0.02]\ntarget_probability = 1e-6\n");
    FAIL("a key sweep without safe_side was accepted");
  } catch (const std::exception& e) {
    CHECK_THAT(e.what(), Catch::Contains("sweep.safe_side: a sweep of drive.stall_torque_Nm's nominal value must "
                                         "say on which side") && Catch::Contains("t:"));
  }
  const std::string spread = "[sweep]\nspread = \"drive.stall_torque_Nm\"\nvalues = [0.001, 0.002]\n"
                             "target_probability = 1e-6\n";
  CHECK(sweep_of(parse(spread)).calc_safe_side() == -1);
  CHECK(sweep_of(parse(spread + "safe_side = \"above\"\n")).calc_safe_side() == +1);
  CHECK(sweep_of(parse(spread + "safe_side = \"below\"\n")).calc_safe_side() == -1);
  CHECK_THROWS_WITH(parse(spread + "safe_side = \"up\"\n"), Catch::Contains("safe_side"));
}

TEST_CASE("a Monte Carlo or stop sweep: the method's row reads [failure], the runs cap is per value", "[sweep]") {
  // The design and stop rows read [failure] only with a [sweep]; the cap is the method's per value
  // times the values (3 here).
  const std::string mc = R"(
[ensemble]
n_runs = 400
master_seed = 5
[failure]
column = "peak_drive_force_N"
above = 3.5
unit = "N"
[[dispersion]]
key = "drive.stall_torque_Nm"
apply = "offset"
distribution = "normal"
std = 0.001
)";
  const std::string sweep = "[sweep]\nkey = \"drive.stall_torque_Nm\"\nsafe_side = \"above\"\nvalues = [0.01, 0.02, 0.04]\n"
                            "target_probability = 1e-2\n";
  const CampaignOptions c = truss::methods::parse_campaign_text(mc + sweep, "mc.toml", ".");
  REQUIRE(c.ensemble.method.options().failure_event() != nullptr);
  CHECK(c.ensemble.method.options().failure_event()->column == "peak_drive_force_N");
  CHECK(calc_max_runs(c) == 3 * 400);
  const CampaignOptions back = truss::methods::parse_campaign_text(resolved_campaign_toml(c), "resolved", ".");
  CHECK(back.ensemble.method.options().failure_event()->threshold == 3.5);
  CHECK(resolved_campaign_toml(back) == resolved_campaign_toml(c));

  const std::string stop = "[ensemble.stop]\ntarget = \"probability_half_width\"\nwidth = 0.05\nmax_runs = 2000\n";
  const CampaignOptions s = truss::methods::parse_campaign_text(mc + stop + sweep, "stop.toml", ".");
  CHECK(s.ensemble.method.name() == "sweep");  // the composite, around the stop rule
  CHECK(s.ensemble.method.options().inner_method()->name() == "stop");
  CHECK(s.ensemble.method.options().failure_event()->kind == FailureKind::above);
  CHECK(calc_max_runs(s) == 3 * 2000);

  auto error_of = [](const std::string& text, const std::vector<std::string>& sets = {}) {
    try {
      truss::methods::parse_campaign_text(text, "bad.toml", ".", sets);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // Without a sweep the design and the stop rule estimate the event's probability too (what a sweep's
  // value is, alone): the same [failure], read by the same rows.
  CHECK(error_of(mc).empty());
  const CampaignOptions alone = truss::methods::parse_campaign_text(mc, "mc.toml", ".");
  CHECK(alone.ensemble.method.options().failure_event()->kind == FailureKind::above);
  CHECK(error_of(mc + "[ensemble.stop]\ntarget = \"probability_half_width\"\nwidth = 0.05\n").empty());
  // A Monte Carlo estimate needs Monte Carlo points.
  CHECK(error_of(mc + "[sweep]\nkey = \"drive.stall_torque_Nm\"\nsafe_side = \"above\"\nvalues = [0.01, 0.02]\ntarget_probability = 0.1\n",
                 {"ensemble.sampling=sobol"})
            .find("ensemble.sampling: \"sobol\" gives no binomial interval of a probability") != std::string::npos);
  // A percentile stop rule estimates no probability.
  CHECK(error_of(mc + "[ensemble.stop]\ntarget = \"percentile_bound\"\noutput = \"peak_drive_force_N\"\n" + sweep)
            .find("ensemble.stop.target: \"percentile_bound\" estimates a percentile, not a probability") !=
        std::string::npos);
  // A sweep without [failure].
  const std::string no_failure = mc.substr(0, mc.find("[failure]")) + mc.substr(mc.find("[[dispersion]]"));
  CHECK(error_of(no_failure + sweep).find("failure: a sweep estimates the probability of a [failure] event") !=
        std::string::npos);
}

TEST_CASE("refinement candidates: evenly inside each bracket, keyed after the listed values", "[sweep]") {
  // Values 0.01, 0.02, 0.04 with refine = 3: candidates at quarters of each bracket, by hand.
  const CampaignOptions c = parse("[sweep]\nkey = \"drive.stall_torque_Nm\"\nsafe_side = \"above\"\nvalues = [0.01, 0.02, 0.04]\n"
                                  "target_probability = 1e-6\nrefine = 3\n");
  REQUIRE(axis(c).refine == 3);
  REQUIRE(axis(c).n_values() == 3);
  REQUIRE(axis(c).n_design_values() == 3 + 2 * 3);
  const double want[] = {0.01, 0.02, 0.04, 0.0125, 0.015, 0.0175, 0.025, 0.03, 0.035};
  for (std::size_t k = 0; k < 9; ++k) CHECK(axis(c).find_value(k) == Approx(want[k]).epsilon(1e-15));
  CHECK(axis(c).find_candidate_index(1, 2) == 8);
  // The most runs: the listed values and one bracket's candidates, each with subset simulation's
  // cap N + (max_levels - 1)(N - N p0) = 100 + 19 x 90 = 1810 (the defaults max_levels 20, p0 0.1).
  CHECK(calc_max_runs(c) == 1810 * (3 + 3));
  // A candidate's run applies its value; its standalone campaign has it and the seed of its index.
  const DimensionLayout L = calc_layout(c);
  std::vector<double> u(static_cast<std::size_t>(L.total), 0.5);
  u[0] = kPhi1;
  u[static_cast<std::size_t>(L.design)] = (7 + 0.5) / 9.0;
  const RunInputs in = calc_run_inputs(c, L, u.data());
  CHECK(in.values.back() == std::vector<double>{axis(c).find_value(7)});
  CHECK(in.scene.drive.stall_torque_Nm == Approx(0.03 + 0.001).epsilon(1e-12));
  const CampaignOptions at = calc_campaign_at(c, 7);
  CHECK(at.base.drive.stall_torque_Nm == axis(c).find_value(7));
  CHECK(at.ensemble.master_seed == c.ensemble.master_seed);
  CHECK_THROWS(calc_campaign_at(c, 9));
  // The resolved TOML keeps it.
  const CampaignOptions back = truss::methods::parse_campaign_text(resolved_campaign_toml(c), "resolved", ".");
  CHECK(axis(back).refine == 3);
  CHECK(resolved_campaign_toml(back) == resolved_campaign_toml(c));

  auto error_of = [](const std::string& sweep) {
    try {
      parse(sweep);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string head = "[sweep]\nkey = \"drive.stall_torque_Nm\"\nsafe_side = \"above\"\nvalues = [0.01, 0.02]\ntarget_probability = 1e-6\n";
  CHECK_THAT(error_of(head + "refine = 21\n"), Catch::Contains("sweep.refine: must lie in [0, 20], got 21"));
  CHECK_THAT(error_of(head + "refine = -1\n"), Catch::Contains("sweep.refine: must lie in [0, 20], got -1"));
  CHECK_THAT(error_of(head + "refine = 1.5\n"), Catch::Contains("sweep.refine"));
}
