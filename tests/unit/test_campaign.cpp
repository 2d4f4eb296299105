// Campaign files: the shipped campaigns parse; every class of bad campaign file is an InputError
// naming the file, the key and the line.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "campaign/campaign.hpp"
#include "campaign/evaluate.hpp"
#include "campaign/motor_declared.hpp"
#include "io/scene_toml.hpp"
#include "methods/method_table.hpp"

using namespace truss::campaign;
namespace fs = std::filesystem;

namespace {
std::string write_tmp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "truss_campaign_tests";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p.string();
}
std::string error_of(const std::string& path, const std::vector<std::string>& sets = {}) {
  try {
    truss::methods::parse_campaign_file(path, sets);
  } catch (const truss::io::InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("the shipped campaigns parse", "[campaign]") {
  const std::string root = TRUSS_SOURCE_DIR;
  const CampaignOptions t1 = truss::methods::parse_campaign_file(root + "/campaigns/table1_dispersed.toml");
  CHECK(t1.ensemble.n_runs == 10000);
  CHECK(t1.ensemble.sampling == truss::campaign::SamplingMethod::latin_hypercube);
  CHECK(t1.base.mast.n_bays == 30);
  CHECK(t1.base.run.output_step_s == 0.0);
  CHECK(t1.dispersions.size() == 8);
  CHECK(t1.dispersions[0].per == Per::bay);
  const CampaignOptions m = truss::methods::parse_campaign_file(root + "/campaigns/motor_torque.toml");
  CHECK(m.base.drive.mode == truss::sim::DriveMode::motor);
  CHECK(m.base.drive.stall_torque_Nm == 0.0052);
  const CampaignOptions b = truss::methods::parse_campaign_file(root + "/campaigns/bay_count.toml", {"ensemble.n_runs=40"});
  CHECK(b.ensemble.n_runs == 40);
  CHECK(b.dispersions[0].values.front() == 10);
  CHECK(b.dispersions[0].values.back() == 60);
  // --set of a scene key
  const CampaignOptions s = truss::methods::parse_campaign_file(root + "/campaigns/bay_count.toml", {"scene.drive.mode=torque"});
  CHECK(s.base.drive.mode == truss::sim::DriveMode::torque);
}

TEST_CASE("bad campaign files name the key and the line", "[campaign][input]") {
  const std::string head = "[ensemble]\nn_runs = 10\nmaster_seed = 1\n";
  struct Bad { std::string text; std::string key; int line; };
  const Bad cases[] = {
      {head + "colour = 3\n", "ensemble.colour", 4},                                   // unknown key
      {head + "[extra]\nx = 1\n", "extra", 4},                                          // unknown table
      {"[ensemble]\nn_runs = -5\n", "ensemble.n_runs", 2},                              // negative count
      {"[ensemble]\nn_runs = 0\n", "ensemble.n_runs", 2},
      {"[ensemble]\nsampling = \"quasi\"\n", "ensemble.sampling", 2},                  // bad enum
      {head + "[[dispersion]]\nkey = \"mast.wing_span_m\"\ndistribution = \"normal\"\nstd = 0.1\n", "mast.wing_span_m", 4},
      {head + "[[dispersion]]\nkey = \"mast.strut_mass_kg\"\ndistribution = \"normal\"\nstd = -0.1\n", "std: must be > 0", 4},
      {head + "[[dispersion]]\nkey = \"mast.strut_mass_kg\"\ndistribution = \"uniform\"\nlower = 0.1\nupper = 0.0\n", "lower", 4},
      {head + "[[dispersion]]\nkey = \"mast.strut_mass_kg\"\ndistribution = \"truncated_normal\"\nmean = 0\nstd = 0.01\nlower = 1\nupper = 2\n",
       "excludes all probability mass", 4},
      {head + "[[dispersion]]\nkey = \"rail.x_m\"\nper = \"bay\"\ndistribution = \"normal\"\nstd = 0.1\n", "not a per-bay key", 4},
      {head + "[[dispersion]]\nkey = \"mast.n_bays\"\napply = \"absolute\"\ndistribution = \"discrete\"\nvalues = [10, 12.5]\n", "integers", 4},
      {head + "[[dispersion]]\nkey = \"mast.n_bays\"\ndistribution = \"normal\"\nstd = 1\n", "discrete", 4},
      {head + "[[dispersion]]\nkey = \"mast.strut_mass_kg\"\ndistribution = \"discrete\"\nvalues = [1, 2]\nweights = [1]\n", "weights", 4},
      {head + "[[dispersion]]\nkey = \"mast.strut_mass_kg\"\ndistribution = \"discrete\"\nvalues = []\n", "values: must not be empty", 4},
      {head + "[[dispersion]]\nkey = \"mast.strut_mass_kg\"\ndistribution = \"lognormal\"\nsigma = 0\n", "sigma: must be > 0", 4},
      {head + "[[dispersion]]\nkey = \"mast.strut_mass_kg\"\ndistribution = \"normal\"\nstd = 0.1\nmean = \"zero\"\n", "expected a number", 8},
      {head + "[scene]\noverrides = { \"rail.beta_deg\" = 95 }\n", "rail.beta_deg", 0},
      {head + "[ensemble\n", "", 4},                                                    // syntax error
      // campaign keys that become [run] keys of every run take those keys' ranges
      {head + "max_run_wall_time_s = 1e308\n", "ensemble.max_run_wall_time_s: must lie in (0, 10000000] s", 4},
      {head + "[output]\nhistory_step_s = 1e308\n", "output.history_step_s: must lie in [0, 1000] s", 5},
      {head + "[output]\nhistory_runs = [3, 0, 3]\n", "output.history_runs: run 3 is listed twice", 5},
  };
  int i = 0;
  for (const Bad& b : cases) {
    const std::string path = write_tmp("bad" + std::to_string(i++) + ".toml", b.text);
    const std::string e = error_of(path);
    INFO(b.text << "\n-> " << e);
    REQUIRE(!e.empty());
    CHECK(e.rfind("error: ", 0) == 0);
    CHECK(e.find(path) != std::string::npos);
    CHECK(e.find(b.key) != std::string::npos);
    // (appended, not ":" + ...: GCC 12 warns -Wrestrict, wrongly, on that operator+ inlined)
    if (b.line > 0) CHECK(e.find(std::string(":").append(std::to_string(b.line)).append(":")) != std::string::npos);
  }
  CHECK(error_of("/nonexistent/campaign.toml").find("cannot read") != std::string::npos);
  const std::string ok = write_tmp("ok.toml", head);
  CHECK(error_of(ok, {"ensemble.n_runs=-3"}).find("ensemble.n_runs") != std::string::npos);
  CHECK(error_of(ok, {"mast.n_bays=3"}).empty());  // a base-scene key, as truss-sim takes it
  CHECK(error_of(ok, {"mast.n_bayz=3"}).find("--set mast.n_bayz=3") != std::string::npos);
  CHECK(error_of(ok, {"foo.bar=3"}).find("only ensemble.*") != std::string::npos);
  CHECK(error_of(ok).empty());
}

TEST_CASE("CampaignOptions::validate names the field that breaks a rule, in code as in files", "[campaign][input]") {
  using namespace truss::campaign;
  CampaignOptions c = truss::methods::parse_campaign_file(TRUSS_SOURCE_DIR "/campaigns/table1_dispersed.toml");
  CHECK(c.validate().empty());
  CampaignOptions bad = c;
  bad.ensemble.n_runs = 0;
  CHECK(bad.validate().rfind("ensemble.n_runs", 0) == 0);
  bad = c;
  bad.dispersions[0].key = "run.rtol";
  CHECK(bad.validate().find("is not a scene key that can be dispersed") != std::string::npos);
  bad = c;
  bad.dispersions[0].std = -1.0;
  CHECK(bad.validate().rfind("dispersion[1]", 0) == 0);
  bad = c;
  bad.dispersions[1] = bad.dispersions[0];
  CHECK_THAT(bad.validate(), Catch::StartsWith("dispersion[2].key") && Catch::Contains("already dispersed at line"));
  bad = c;
  bad.output.history_runs = {c.ensemble.n_runs};
  CHECK(bad.validate().rfind("output.history_runs", 0) == 0);
  bad = c;
  bad.ensemble.sampling = SamplingMethod::saltelli;
  bad.ensemble.n_runs = 11;  // blocks of 10 (8 dispersions + 2)
  CHECK_THAT(bad.validate(), Catch::StartsWith("ensemble.n_runs") && Catch::Contains("multiple of 10"));
  bad.ensemble.n_runs = 10;  // one block: not enough for an interval
  CHECK_THAT(bad.validate(), Catch::Contains("at least 20"));
  // One set of rules: the same broken rule in a file is refused by the parser with the file's line.
  const std::string file = "[ensemble]\nn_runs = 30\nsampling = \"saltelli\"\n[[dispersion]]\nkey = \"rail.x_m\"\n"
                           "distribution = \"normal\"\nstd = 0.001\napply = \"offset\"\n";
  CHECK_THAT(error_of(write_tmp("rules.toml", file), {"ensemble.n_runs=4"}),
             Catch::Contains("--set ensemble.n_runs=4") && Catch::Contains("multiple of 3 and at least 6"));
  CHECK(error_of(write_tmp("rules.toml", file)).empty());  // 30 = 10 blocks of 3
  CHECK_THAT(error_of(write_tmp("rules.toml", file), {"ensemble.sampling=sobol", "ensemble.n_runs=5000000000"}),
             Catch::Contains("--set ensemble.n_runs=5000000000") && Catch::Contains("sobol supports at most 2^32 runs"));
}

TEST_CASE("a campaign declares its motor by its own lines, never by the scene file's defaults", "[campaign]") {
  const std::string root = TRUSS_SOURCE_DIR;
  auto declared = [&](const std::string& name, const std::vector<std::string>& sets = {}) {
    return find_motor_declared_by(truss::methods::parse_campaign_file(root + "/campaigns/" + name, sets));
  };
  // table1_dispersed.toml line 29: [scene.drive] stall_torque_Nm = 0.030.
  CHECK(declared("table1_dispersed.toml") == root + "/campaigns/table1_dispersed.toml:29");
  // bay_count and free_rail_miss run the scene file's default motor: nothing declared.
  CHECK(declared("bay_count.toml").empty());
  CHECK(declared("free_rail_miss.toml").empty());
  CHECK(declared("bay_count.toml", {"drive.no_load_speed_rad_per_s=90"}) == "--set drive.no_load_speed_rad_per_s=90");
  CHECK(declared("bay_count.toml", {"scene.drive.stall_torque_Nm=0.04"}).find("stall_torque_Nm") != std::string::npos);
  CHECK(declared("motor_torque.toml") == "drive.mode = \"motor\"");  // the motor drives the mast
  const std::string text = "[ensemble]\nn_runs = 10\n[[dispersion]]\nkey = \"drive.stall_torque_Nm\"\n"
                           "distribution = \"normal\"\nstd = 0.01\n";
  CHECK(find_motor_declared_by(truss::methods::parse_campaign_text(text, "c.toml", root + "/campaigns")) ==
        "[[dispersion]] drive.stall_torque_Nm (line 3)");
}
