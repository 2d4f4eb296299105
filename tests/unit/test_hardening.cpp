// Hostile input: every numeric scene key's hard range enforced in files, --set and
// campaign draws; plausibility warnings from the typical ranges; geometry
// errors naming the keys involved and their origins; bounded input files; campaign messages that
// name the --set or the campaign line; the resource check before any work.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/evaluate.hpp"
#include "methods/method_table.hpp"
#include "results/resources.hpp"
#include "sampling/sampling.hpp"
#include "io/scene_toml.hpp"
#include "sim/scene_keys.hpp"

using Catch::Matchers::Contains;
using truss::io::InputError;
namespace sim = truss::sim;

namespace {
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "<no InputError>";
}
std::vector<std::string> warnings_of(const std::string& text, const std::vector<std::string>& sets = {}) {
  std::vector<truss::io::SceneSetting> s;
  for (const auto& a : sets) s.push_back({a, {}});
  std::vector<std::string> w;
  truss::io::parse_scene_text_with(text, "scene.toml", s, &w);
  return w;
}
// The record of a Monte Carlo run (uniforms counter_uniform(seed, run, j)).
void record_of(const truss::campaign::CampaignContext& ctx, std::int64_t run, std::string& out) {
  std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
  for (std::size_t j = 0; j < u.size(); ++j)
    u[j] = truss::sampling::counter_uniform(ctx.options.ensemble.master_seed, run, static_cast<std::int64_t>(j));
  truss::campaign::append_run_record(ctx, u.data(), {run, 0, 0}, out);
}
}  // namespace

TEST_CASE("key table: defaults lie in the typical range, typical ranges inside the hard ones", "[hardening][keys]") {
  const sim::SceneOptions defaults;  // Table 1 and the project defaults: a plausible mast
  for (const auto& k : sim::scene_keys()) {
    if (k.kind == sim::KeyKind::enumeration) continue;
    INFO(k.dotted());
    CHECK(k.hard.lo <= k.typical.lo);
    CHECK(k.typical.hi <= k.hard.hi);
    CHECK(std::isfinite(k.hard.hi));  // every key has a finite upper bound: 1e308 is refused
    if (const auto v = sim::key_value(k, defaults)) {
      CHECK(sim::check_hard_range(k, *v).empty());
      CHECK(sim::check_typical_range(k, *v).empty());
    }
  }
}

TEST_CASE("1e308 in any numeric key is refused at parse time with its line or --set", "[hardening][keys]") {
  for (const auto& k : sim::scene_keys()) {
    if (k.kind == sim::KeyKind::enumeration) continue;
    INFO(k.dotted());
    const std::string value = k.kind == sim::KeyKind::integer ? "9000000000000000000" : "1e308";
    const std::string file = error_of([&] {
      truss::io::parse_scene_text(fmt::format("[{}]\n{} = {}\n", k.table, k.key, value), "scene.toml");
    });
    CHECK_THAT(file, Contains("scene.toml:2:") && Contains(k.dotted()));
    const std::string set = error_of([&] { truss::io::parse_scene_text("", "scene.toml", {k.dotted() + "=" + value}); });
    CHECK_THAT(set, Contains("--set " + k.dotted() + "=" + value));
    // and -1e308, NaN and infinity too (NaN compares false with every bound)
    for (const char* v : {"-1e308", "nan", "inf"}) {
      if (k.kind == sim::KeyKind::integer) break;
      CHECK_THAT(error_of([&] { truss::io::parse_scene_text("", "s.toml", {k.dotted() + "=" + v}); }), Contains(k.dotted()));
    }
  }
  CHECK_THAT(error_of([] { truss::io::parse_scene_text("[mast]\nstrut_mass_kg = 1e308\n", "scene.toml"); }),
             Contains("must lie in (0, 10000] kg, got 1e+308"));
}

TEST_CASE("plausibility warnings name the key, its origin and the typical range", "[hardening][warnings]") {
  // 5.2 N m where 5.2 mN m was meant: runs, with a warning.
  auto w = warnings_of("[drive]\nmode = \"motor\"\nstall_torque_Nm = 5.2\n");
  REQUIRE(w.size() == 1);
  CHECK_THAT(w[0], Contains("warning: scene.toml:3:") && Contains("drive.stall_torque_Nm = 5.2 N m") &&
                       Contains("typical range [0.0001, 1] N m") && Contains("milli-units? 0.0052 N m"));
  w = warnings_of("", {"drive.speed_m_per_s=100"});
  REQUIRE(w.size() == 1);
  CHECK_THAT(w[0], Contains("warning: --set drive.speed_m_per_s=100:") && Contains("[0.0001, 1] m/s"));
  // a frame side typed in mm (360 for 0.36 m)
  w = warnings_of("[mast]\nframe_side_m = 360\n");
  REQUIRE(w.size() == 1);
  CHECK_THAT(w[0], Contains("mast.frame_side_m = 360 m") && Contains("0.36 m would be typical"));
  // values at the edges of the typical range, and defaults, warn nothing
  CHECK(warnings_of("[drive]\nstall_torque_Nm = 1.0\nspeed_m_per_s = 0.0001\n").empty());
  CHECK(warnings_of("").empty());
}

TEST_CASE("geometry errors name the keys involved and where each came from", "[hardening][geometry]") {
  const std::string e = error_of([] { truss::io::parse_scene_text("[rail]\nbeta_deg = 80\n", "scene.toml", {"rail.x_m=0.05"}); });
  CHECK_THAT(e, Contains("never meets the rail") && Contains("keys involved"));
  CHECK_THAT(e, Contains("rail.beta_deg = 80 deg (scene.toml:2)"));
  // A beta whose cotangent overflows (5e-324 deg is 0 rad in doubles) is refused with its value,
  // not reported as "0 deg >= 45 deg".
  const std::string tiny = error_of([] { truss::io::parse_scene_text("", "scene.toml", {"rail.beta_deg=5e-324"}); });
  CHECK_THAT(tiny, Contains("rail.beta_deg: 5e-324 deg is too small") && !Contains("= 0 deg") && !Contains(">= 45"));
  CHECK(error_of([] { truss::io::parse_scene_text("", "scene.toml", {"rail.beta_deg=1e-300"}); }).find("too small") ==
        std::string::npos);
  CHECK_THAT(e, Contains("rail.x_m = 0.05 m (--set rail.x_m=0.05)"));
  CHECK_THAT(e, Contains("rail.y_m = 0.15 m (default)"));
  CHECK_THAT(e, Contains("mast.strut_length_m = 0.18 m (default)"));
}

TEST_CASE("input files are bounded in size", "[hardening][files]") {
  CHECK_THAT(error_of([] { truss::io::parse_scene_file("/dev/zero"); }),
             Contains("/dev/zero: cannot read scene file: larger than the limit"));
  CHECK_THAT(error_of([] { truss::io::read_input_file("/dev/zero", "campaign file", 1000); }), Contains("limit of 1000 bytes"));
  CHECK_THAT(error_of([] { truss::io::parse_scene_file("/"); }), Contains("is a directory"));
  // the limit exactly, and one byte past it; a file of several read blocks comes back whole
  const std::string dir = std::filesystem::temp_directory_path() / "truss_hardening_files";
  std::filesystem::create_directories(dir);
  std::string text(200'001, 'x');
  for (std::size_t i = 0; i < text.size(); ++i) text[i] = static_cast<char>('a' + (i * 7919) % 26);
  std::ofstream(dir + "/big.toml", std::ios::binary) << text;
  CHECK(truss::io::read_input_file(dir + "/big.toml", "scene file", 200'001) == text);
  CHECK_THAT(error_of([&] { truss::io::read_input_file(dir + "/big.toml", "scene file", 200'000); }),
             Contains("big.toml: cannot read scene file: larger than the limit of 200000 bytes"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("campaign messages name the --set or the campaign line", "[hardening][campaign]") {
  const std::string text = "[ensemble]\nn_runs = 10\n[scene]\nfile = \"/\"\n";
  // scene.file = "/" points at the campaign's line 4
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text(text, "c.toml", "."); }),
             Contains("error: c.toml:4: scene.file = \"/\"") && Contains("is a directory"));
  const std::string ok = "[ensemble]\nn_runs = 10\n";
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text(ok, "c.toml", ".", {"campaign.name=1"}); }),
             Contains("error: --set campaign.name=1: campaign.name: expected a string"));
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text(ok, "c.toml", ".", {"ensemble.n_run=5"}); }),
             Contains("error: --set ensemble.n_run=5: unknown key 'ensemble.n_run'"));
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text(ok, "c.toml", ".", {"ensemble.n_runs=0"}); }),
             Contains("--set ensemble.n_runs=0"));
  // "did you mean" for campaign keys, as for scene keys: the closest known key of the table, none
  // for a name far from every key.
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text("[ensemble]\nn_run = 2000\n", "c.toml", "."); }),
             Contains("error: c.toml:2: unknown key 'ensemble.n_run'; did you mean ensemble.n_runs?"));
  CHECK_THAT(error_of([&] {
               truss::methods::parse_campaign_text(ok + "[ensemble.stop]\ntarget = \"percentile_bound\"\nwidht = 0.1\n",
                                                    "c.toml", ".");
             }),
             Contains("did you mean ensemble.stop.width?"));
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text("[ensembel]\nn_runs = 10\n", "c.toml", "."); }),
             Contains("unknown table 'ensembel'; did you mean ensemble?"));
  const std::string far = error_of([&] { truss::methods::parse_campaign_text("[ensemble]\ncolour = 3\n", "c.toml", "."); });
  CHECK_THAT(far, Contains("unknown key 'ensemble.colour' (known:") && !Contains("did you mean"));
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text(ok, "c.toml", ".", {"mast.frame_mass_kg=1e308"}); }),
             Contains("--set mast.frame_mass_kg=1e308") && Contains("must lie in"));
  // base-scene warnings are kept for the driver to print
  const auto c = truss::methods::parse_campaign_text(ok, "c.toml", ".", {"drive.speed_m_per_s=100"});
  REQUIRE(c.warnings.size() == 1);
  CHECK_THAT(c.warnings[0], Contains("--set drive.speed_m_per_s=100"));
}

TEST_CASE("a dispersed value outside its hard range is a named failed run", "[hardening][campaign]") {
  // frame mass drawn uniformly in [2e5, 3e5] kg, above the hard limit of 1e5 kg: the file is
  // refused before any run (implausible dispersion); built in code past that check, every run is
  // invalid_input with the key, the frame and the range in its message; nothing throws.
  const std::string text =
      "[ensemble]\nn_runs = 4\n[scene.mast]\nn_bays = 3\n[[dispersion]]\nkey = \"mast.frame_mass_kg\"\nper = \"frame\"\n"
      "apply = \"absolute\"\ndistribution = \"uniform\"\nlower = 2e5\nupper = 3e5\n";
  CHECK_THAT(error_of([&] { truss::methods::parse_campaign_text(text, "c.toml", "."); }),
             Contains("c.toml:5: dispersion[1]: mast.frame_mass_kg (absolute uniform) is implausible"));
  auto past_the_check = [](std::string file, const std::string& lower, const std::string& upper, double lo, double hi) {
    file.replace(file.find(lower), lower.size(), "lower = 1");
    file.replace(file.find(upper), upper.size(), "upper = 2");
    truss::campaign::CampaignOptions o = truss::methods::parse_campaign_text(file, "c.toml", ".");
    o.dispersions[0].lower = lo;
    o.dispersions[0].upper = hi;
    return o;
  };
  const truss::campaign::CampaignContext ctx(past_the_check(text, "lower = 2e5", "upper = 3e5", 2e5, 3e5));
  for (std::int64_t run = 0; run < 4; ++run) {
    std::string rec;
    REQUIRE_NOTHROW(record_of(ctx, run, rec));
    const truss::campaign::RecordView r(rec, ctx.record);
    CHECK(r.status() == static_cast<std::int8_t>(sim::RunStatus::invalid_input));
    CHECK_THAT(std::string(r.message()), Contains("mast.frame_mass_kg: must lie in (0, 100000] kg") && Contains("(frame 0)"));
  }
  // a per-run draw (speed in [1001, 2000] m/s, hard limit 1000 m/s): the scene check names it
  const std::string per_run =
      "[ensemble]\nn_runs = 4\n[scene.mast]\nn_bays = 3\n[[dispersion]]\nkey = \"drive.speed_m_per_s\"\n"
      "apply = \"absolute\"\ndistribution = \"uniform\"\nlower = 1001\nupper = 2000\n";
  const truss::campaign::CampaignContext ctx2(past_the_check(per_run, "lower = 1001", "upper = 2000", 1001, 2000));
  for (std::int64_t run = 0; run < 4; ++run) {
    std::string rec;
    record_of(ctx2, run, rec);
    const truss::campaign::RecordView r(rec, ctx2.record);
    CHECK(r.status() == static_cast<std::int8_t>(sim::RunStatus::invalid_input));
    CHECK_THAT(std::string(r.message()), Contains("drive.speed_m_per_s: must lie in (0, 1000] m/s"));
  }
}

TEST_CASE("resource check: n_runs against memory and disk, estimates in the message", "[hardening][resources]") {
  const std::string text = "[ensemble]\nn_runs = 10\n";
  auto ctx_for = [&](std::int64_t n) {
    return truss::campaign::CampaignContext(
        truss::methods::parse_campaign_text(text, "c.toml", ".", {fmt::format("ensemble.n_runs={}", n)}));
  };
  const auto small = ctx_for(10);
  CHECK(truss::results::check_resources(small, "out.h5").empty());
  const auto e10 = truss::results::estimate_resources(small);
  // The estimate is linear in n_runs (it holds no per-campaign constant).
  const auto big = ctx_for(100000000000);
  const auto e11 = truss::results::estimate_resources(big);
  CHECK(e11.memory_bytes == Catch::Detail::Approx(e10.memory_bytes * 1e10));
  // each run holds at least its ~20 f64 summary values: > 100 bytes
  CHECK(e10.bytes_per_run < 64.0);  // results stream to the file: flags, to-do entry and one read-back column per run
  const std::string msg = truss::results::check_resources(big, "out.h5");
  CHECK_THAT(msg, Contains("ensemble.n_runs = 100000000000") && Contains("in memory") && Contains("bytes per run"));
  // 2^63 - 1 runs: refused the same way (no overflow in the estimate)
  for (const char* sampling : {"monte_carlo", "sobol", "latin_hypercube"}) {
    INFO(sampling);
    const std::string err = error_of([&] {
      const truss::campaign::CampaignContext c(truss::methods::parse_campaign_text(
          text, "c.toml", ".", {"ensemble.n_runs=9223372036854775807", std::string("ensemble.sampling=") + sampling}));
      if (const std::string m = truss::results::check_resources(c, "out.h5"); !m.empty()) throw InputError(m);
    });
    CHECK_THAT(err, Contains("9223372036854775807") || Contains("at most 2^"));
  }
  // A run cap from [ensemble.stop] is named by the key the user wrote.
  const truss::campaign::CampaignContext stop(truss::methods::parse_campaign_text(
      "[ensemble]\nn_runs = 100\n[ensemble.stop]\ntarget = \"probability_relative_half_width\"\nwidth = 0.5\n",
      "c.toml", ".", {"ensemble.stop.max_runs=1000000000000"}));
  const std::string stop_msg = truss::results::check_resources(stop, "out.h5");
  CHECK_THAT(stop_msg, Contains("ensemble.stop.max_runs = 1000000000000") && Contains("in memory") &&
                           !Contains("ensemble.n_runs"));
}
