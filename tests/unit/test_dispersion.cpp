// Dispersions: the dimension layout, the mapping from uniforms to a run's scene and mast, and
// that dispersed runs simulate (every run of a small Table-1 campaign ends ok, energy balanced).
#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "campaign/dispersion.hpp"
#include "campaign_fixtures.hpp"
#include "methods/method_table.hpp"
#include "sampling/sampling.hpp"
#include "sim/simulate.hpp"

using namespace truss::campaign;
using truss::sampling::SamplePlan;

TEST_CASE("dimension layout: per-bay and per-frame keys own n_max and n_max + 1 dimensions", "[dispersion]") {
  const std::string root = TRUSS_SOURCE_DIR;
  const CampaignOptions t1 = truss::methods::parse_campaign_file(root + "/campaigns/table1_dispersed.toml");
  const DimensionLayout L = calc_layout(t1);
  CHECK(L.n_bays_max == 30);
  // bay keys: mass, stiffness, strut length, free length (4 x 30); frame keys: mass, side (2 x 31); rail x, y
  CHECK(L.total == 4 * 30 + 2 * 31 + 2);
  const CampaignOptions bc = truss::methods::parse_campaign_file(root + "/campaigns/bay_count.toml");
  const DimensionLayout Lb = calc_layout(bc);
  CHECK(Lb.n_bays_max == 60);
  CHECK(Lb.total == 1 + 60);
}

TEST_CASE("uniforms map to the dispersed values through the inverse CDFs", "[dispersion]") {
  const std::string root = TRUSS_SOURCE_DIR;
  const CampaignOptions t1 = truss::methods::parse_campaign_file(root + "/campaigns/table1_dispersed.toml");
  const DimensionLayout L = calc_layout(t1);
  std::vector<double> u(static_cast<std::size_t>(L.total), 0.5);  // medians: every draw at its nominal
  RunInputs in = calc_run_inputs(t1, L, u.data());
  CHECK(in.mast.bay(7).strut_mass_kg == Approx(0.1).epsilon(1e-15));
  CHECK(in.mast.bay(7).strut_length_m == Approx(0.18).epsilon(1e-15));
  CHECK(in.scene.rail.x_m == Approx(0.08).epsilon(1e-15));
  // one sigma up on the strut mass of bay 3 only: 0.1 (1 + 0.05 / 3)
  const double one_sigma = 0.5 * std::erfc(-1.0 / std::sqrt(2.0));
  u[static_cast<std::size_t>(L.offset[0] + 2)] = one_sigma;
  in = calc_run_inputs(t1, L, u.data());
  CHECK(in.mast.bay(3).strut_mass_kg == Approx(0.1 * (1 + 0.05 / 3)).epsilon(1e-12));
  CHECK(in.mast.bay(4).strut_mass_kg == Approx(0.1).epsilon(1e-15));
  CHECK(in.values[0][2] == in.mast.bay(3).strut_mass_kg);
  // J_c follows the dispersed strut (slender rod) when it is not given
  CHECK(in.mast.bay(3).strut_inertia_kg_m2 == Approx(in.mast.bay(3).strut_mass_kg * 0.18 * 0.18 / 12).epsilon(1e-12));
  // uniform tolerance at u -> 1: +0.5 mm on the strut length of bay 5
  u[static_cast<std::size_t>(L.offset[3] + 4)] = 1.0 - 1e-12;
  in = calc_run_inputs(t1, L, u.data());
  CHECK(in.mast.bay(5).strut_length_m == Approx(0.1805).epsilon(1e-9));
}

TEST_CASE("a drawn bay count sizes the mast; bays beyond it are NaN in the inputs", "[dispersion]") {
  const std::string root = TRUSS_SOURCE_DIR;
  const CampaignOptions bc = truss::methods::parse_campaign_file(root + "/campaigns/bay_count.toml");
  const DimensionLayout L = calc_layout(bc);
  std::vector<double> u(static_cast<std::size_t>(L.total), 0.5);
  u[0] = 0.01;  // first of 11 equally weighted values
  RunInputs in = calc_run_inputs(bc, L, u.data());
  CHECK(in.mast.n_bays() == 10);
  CHECK(in.values[0][0] == 10);
  CHECK(std::isfinite(in.values[1][9]));
  CHECK(std::isnan(in.values[1][10]));
  u[0] = 0.99;
  in = calc_run_inputs(bc, L, u.data());
  CHECK(in.mast.n_bays() == 60);
}

TEST_CASE("dispersed Table-1 runs simulate and balance energy; draws depend on the run index only", "[dispersion]") {
  const std::string root = TRUSS_SOURCE_DIR;
  CampaignOptions t1 = truss::methods::parse_campaign_file(root + "/campaigns/table1_dispersed.toml", {"ensemble.n_runs=24"});
  const DimensionLayout L = calc_layout(t1);
  const SamplePlan plan(SamplingMethod::latin_hypercube, t1.ensemble.n_runs, L.total, t1.ensemble.master_seed);
  REQUIRE(plan.validate().empty());
  std::vector<double> u(static_cast<std::size_t>(L.total)), u2(u.size());
  double min_mass = 1e9, max_mass = 0;
  for (std::int64_t i = t1.ensemble.n_runs - 1; i >= 0; --i) {  // any order gives the same draws
    plan.calc_uniforms(i, u.data());
    plan.calc_uniforms(i, u2.data());
    REQUIRE(u == u2);
    const RunInputs in = calc_run_inputs(t1, L, u.data());
    const auto r = truss::sim::simulate(in.scene, in.mast);
    INFO("run " << i << ": " << r.message);
    REQUIRE(r.status == truss::sim::RunStatus::ok);
    CHECK(std::abs(r.energy_residual_J) < 1e-12 * r.drive_work_J);
    for (const auto& b : in.mast.bays) { min_mass = std::min(min_mass, b.strut_mass_kg); max_mass = std::max(max_mass, b.strut_mass_kg); }
  }
  // +-5 % at 3 sigma: 24 x 30 draws spread over a few sigma, never beyond ~ +-10 %
  CHECK(min_mass < 0.1 * (1 - 0.02));
  CHECK(max_mass > 0.1 * (1 + 0.02));
  CHECK(min_mass > 0.09);
  CHECK(max_mass < 0.11);
}

TEST_CASE("implausible dispersions are named before any run; plausible ones pass", "[dispersion][plausible]") {
  const std::string root = TRUSS_SOURCE_DIR;
  CampaignOptions c = truss::methods::parse_campaign_file(root + "/campaigns/table1_dispersed.toml", {"ensemble.n_runs=24"});
  for (std::size_t i = 0; i < c.dispersions.size(); ++i) CHECK(check_dispersion_draws(c, i).empty());
  // A percentage typed as a fraction: std = 2 (200 %) on a relative strut mass. At -3 sigma the
  // draw is -6, the mass 0.1 (1 - 6) = -0.5 kg (-0.49999 at the quantile -2.99998 sigma); the
  // message names the quantile, the value and the refusal.
  c.dispersions[0].std = 2.0;
  const std::string e = check_dispersion_draws(c, 0);
  CHECK_THAT(e, Catch::Contains("mast.strut_mass_kg") && Catch::Contains("0.135 % quantile") &&
                    Catch::Contains("= -0.49999") && Catch::Contains("non-positive strut mass") &&
                    Catch::Contains("takes a fraction"));
  // The edge: the draw at -3 sigma is -3 std, so a relative std just under 1/3 keeps every mass
  // positive and one just over makes it negative (the normal quantile 0.00135 is -3.0000 sigma).
  c.dispersions[0].std = 0.33;
  CHECK(check_dispersion_draws(c, 0).empty());
  c.dispersions[0].std = 0.34;
  CHECK_FALSE(check_dispersion_draws(c, 0).empty());
  // A discrete table: every value is checked, whatever its weight.
  c.dispersions[0].distribution = DistributionKind::discrete;
  c.dispersions[0].values = {-0.01, 0.0, 0.01};
  c.dispersions[0].weights = {1.0, 1.0, 1.0};
  CHECK(check_dispersion_draws(c, 0).empty());
  c.dispersions[0].values = {-1.5, 0.0, 0.01};
  c.dispersions[0].weights = {0.001, 1.0, 1.0};
  CHECK_THAT(check_dispersion_draws(c, 0), Catch::Contains("its value -1.5"));
}

TEST_CASE("a length moved past 20 % of its nominal is refused with the value it would give", "[dispersion][plausible]") {
  // Millimetres typed as metres on the diagonals' free length (Table 1: 0.45 m): an offset uniform
  // of +-0.3 m reaches 0.45 - 0.3 = 0.15 m at its lower end (every draw lies inside [lower, upper]),
  // 66.7 % of the nominal: refused at the dispersion's line, naming the value and the slip.
  const std::string head = "[ensemble]\nn_runs = 100\n[[dispersion]]\nkey = \"mast.diagonal_free_length_m\"\n";
  auto error_of = [&](const std::string& rest) { return truss::campaign::test::campaign_error(head + rest, "c.toml"); };
  const std::string e = error_of("apply = \"offset\"\ndistribution = \"uniform\"\nlower = -0.3\nupper = 0.3\n");
  CHECK_THAT(e, Catch::Contains("c.toml:3: dispersion[1]: mast.diagonal_free_length_m (offset uniform) is "
                                "implausible: its lower end, a draw of -0.3, gives mast.diagonal_free_length_m = "
                                "0.15 m") &&
                    Catch::Contains("a length moved 66.7 % from its nominal 0.45 m") &&
                    Catch::Contains("millimetres typed as metres? -0.3 mm is -0.0003 m"));
  // The edge, relative: +-19 % at the uniform's ends runs, +-21 % is refused (a relative draw is the
  // share itself); the same in millimetres (+-0.5 mm, the shipped tolerance) runs.
  CHECK(error_of("apply = \"relative\"\ndistribution = \"uniform\"\nlower = -0.19\nupper = 0.19\n").empty());
  CHECK_THAT(error_of("apply = \"relative\"\ndistribution = \"uniform\"\nlower = -0.21\nupper = 0.21\n"),
             Catch::Contains("a length moved 21 % from its nominal 0.45 m"));
  CHECK(error_of("apply = \"offset\"\ndistribution = \"uniform\"\nlower = -0.0005\nupper = 0.0005\n").empty());
  // A normal draw is judged at 3 sigma: std = 6 % (18 % at 3 sigma) runs, 7 % (21 %) is refused.
  CHECK(error_of("apply = \"relative\"\ndistribution = \"normal\"\nstd = 0.06\n").empty());
  CHECK_THAT(error_of("apply = \"relative\"\ndistribution = \"normal\"\nstd = 0.07\n"),
             Catch::Contains("its 0.135 % quantile (-3 sigma)") && Catch::Contains("a percentage typed as a fraction"));
  // The key table's hard range, judged at a uniform's ends: a speed drawn uniformly in [500, 1000.5]
  // m/s has 99.865 % of its draws below 1000 m/s (the limit) but its upper end past it: refused.
  CHECK_THAT(truss::campaign::test::campaign_error("[ensemble]\nn_runs = 100\n[[dispersion]]\n"
                                                   "key = \"drive.speed_m_per_s\"\napply = \"absolute\"\n"
                                                   "distribution = \"uniform\"\nlower = 500\nupper = 1000.5\n",
                                                   "c.toml"),
             Catch::Contains("its upper end, a draw of 1000.5, gives drive.speed_m_per_s = 1000.5 m/s, which the "
                             "model refuses (drive.speed_m_per_s: must lie in (0, 1000] m/s"));
  // Not a length: a rail foot offset (a position, of either sign) moves freely within the model's range.
  CHECK(truss::campaign::test::campaign_error("[ensemble]\nn_runs = 100\n[[dispersion]]\nkey = \"rail.x_m\"\n"
                                              "apply = \"offset\"\ndistribution = \"uniform\"\nlower = -0.02\n"
                                              "upper = 0.02\n", "c.toml")
            .empty());
}
