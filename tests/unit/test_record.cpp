// A campaign's run record (campaign/record.hpp, campaign/evaluate.hpp): its layout, a run's record
// against the simulation it comes from, its refusals; statistics against hand-computed order
// statistics; the resolved campaign text.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "campaign/campaign.hpp"
#include "campaign/evaluate.hpp"
#include "io/scene_toml.hpp"
#include "methods/method_table.hpp"
#include "sim/simulate.hpp"
#include "util/bytes.hpp"
#include "campaign_fixtures.hpp"

using namespace truss::campaign;
using namespace truss::sampling;
using truss::campaign::test::small_campaign;
namespace sim = truss::sim;

namespace {

// The point of run `run` of the campaign's one-round design: uniforms keyed by (seed, run).
std::vector<double> point(const CampaignContext& ctx, std::int64_t run) {
  std::vector<double> u(static_cast<std::size_t>(ctx.dims.total));
  for (std::size_t j = 0; j < u.size(); ++j)
    u[j] = counter_uniform(ctx.options.ensemble.master_seed, run, static_cast<std::int64_t>(j));
  return u;
}

// Equal, or both NaN (a quantity the run did not reach).
bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

std::string record_of(const CampaignContext& ctx, std::int64_t run, std::int64_t rank) {
  std::string out;
  append_run_record(ctx, point(ctx, run).data(), {run, 3, rank}, out);
  return out;
}

// A record with its rank and wall time zeroed: the part that depends on (campaign, point, run) only.
std::string reproducible(const CampaignContext& ctx, std::string rec) {
  const auto& f = ctx.record.fields();
  truss::util::put_at(rec.data() + f[RecordLayout::kRank].offset, std::int64_t{0});
  truss::util::put_at(rec.data() + f[RecordLayout::kWallTime].offset, 0.0);
  return rec;
}

}  // namespace

TEST_CASE("the record layout: head fields, outputs, per-bay outputs, inputs, packed in order", "[campaign][record]") {
  const CampaignContext ctx(small_campaign());
  const RecordLayout& L = ctx.record;
  const auto& f = L.fields();
  REQUIRE(f.size() > 10);
  CHECK(f[RecordLayout::kRun].name == "run_index");
  CHECK(f[RecordLayout::kRound].name == "round");
  CHECK(f[RecordLayout::kStatus].type == ValueType::status);
  CHECK(f[RecordLayout::kRank].group == Group::timing);
  CHECK(f[RecordLayout::kWallTime].name == "run_wall_time_s");
  std::size_t offset = 0, inputs = 0;
  for (const Field& x : f) {
    CHECK(x.offset == offset);  // no gaps, no overlaps
    offset += x.bytes();
    CHECK(!x.units.empty());
    if (x.group == Group::inputs) inputs += static_cast<std::size_t>(x.width);
  }
  CHECK(L.fixed_bytes() == offset);
  CHECK(inputs == 5 + 6 + 1);  // per bay, per frame (n + 1), per run
  const Field& frame_side = f[static_cast<std::size_t>(std::find_if(f.begin(), f.end(), [](const Field& x) {
                                return x.name == "mast.frame_side_m";
                              }) - f.begin())];
  CHECK(frame_side.scale == Scale::frame);
  CHECK(frame_side.units == "m");
  CHECK(L.find_output("peak_drive_force_N") > 0);
  CHECK(L.find_output("n_bays") < 0);  // an int64 output: not a float64 one
  CHECK(L.find_output("no_such_output") < 0);
}

TEST_CASE("a run's record holds what the simulation of its dispersed scene gives", "[campaign][record]") {
  const CampaignContext ctx(small_campaign());
  const RecordLayout& L = ctx.record;
  const std::string a = record_of(ctx, 5, 0);
  REQUIRE(L.check(a).empty());
  const RecordView v(a, L);
  CHECK(v.run() == 5);
  CHECK(v.round() == 3);
  CHECK(v.rank() == 0);
  CHECK(v.status() == 0);
  CHECK(v.message().empty());
  CHECK(v.wall_time_s() > 0.0);
  // The simulation again, by hand: the dispersed scene at the same point, simulated.
  const RunInputs in = calc_run_inputs(ctx.options, ctx.dims, point(ctx, 5).data());
  sim::SceneOptions scene = in.scene;
  scene.run.max_wall_time_s = ctx.options.ensemble.max_run_wall_time_s;
  const sim::RunResult r = sim::simulate(scene, in.mast);
  std::size_t k = 0;
  for (std::size_t i = 0; i < L.fields().size(); ++i) {
    const Field& f = L.fields()[i];
    if (f.run && f.type == ValueType::f64) CHECK(same(v.f64(i), std::get<double>(f.run->get(r))));
    if (f.run && f.type == ValueType::i64) CHECK(v.i64(i) == std::get<std::int64_t>(f.run->get(r)));
    for (int b = 0; f.bay && b < f.width; ++b)
      CHECK(same(v.f64(i, b), std::get<double>(f.bay->get(r.bays[static_cast<std::size_t>(b)]))));
    if (f.dispersion >= 0) {
      const auto& values = in.values[static_cast<std::size_t>(f.dispersion)];
      for (int j = 0; j < f.width; ++j) CHECK(same(v.f64(i, j), values[static_cast<std::size_t>(j)]));
      k += static_cast<std::size_t>(f.width);
    }
  }
  CHECK(k == static_cast<std::size_t>(ctx.dims.total));
  // A pure function of (campaign, point, run): only the rank and the wall time depend on where it ran.
  CHECK(reproducible(ctx, a) == reproducible(ctx, record_of(ctx, 5, 3)));
  CHECK(reproducible(ctx, a) != reproducible(ctx, record_of(ctx, 6, 0)));
}

TEST_CASE("a record that is not one of this campaign's is refused, with what is wrong", "[campaign][record]") {
  const CampaignContext ctx(small_campaign());
  const RecordLayout& L = ctx.record;
  std::string rec;
  RecordWriter w(L, rec);
  w.set_status(sim::RunStatus::stall);
  w.finish("stall: the motor");
  REQUIRE(L.check(rec).empty());
  const RecordView v(rec, L);
  CHECK(v.message() == "stall: the motor");
  CHECK(std::isnan(v.f64(RecordLayout::kWallTime)));  // a float64 not set is NaN
  CHECK(v.run() == 0);                                 // an integer not set is 0
  CHECK_THAT(L.check(std::string_view(rec).substr(0, rec.size() - 1)), Catch::Contains("its message makes it"));
  CHECK_THAT(L.check(rec + "x"), Catch::Contains("its message makes it"));
  CHECK_THAT(L.check(std::string_view(rec).substr(0, 10)), Catch::Contains("shorter than"));
  std::string bad = rec;
  bad[L.fields()[RecordLayout::kStatus].offset] = 42;
  CHECK_THAT(L.check(bad), Catch::Contains("unknown status 42"));
  // Another campaign (two more bays, no dispersions): its records are longer.
  const CampaignContext other(truss::methods::parse_campaign_text("[ensemble]\nn_runs = 4\n[scene.mast]\nn_bays = 7\n", "o.toml", "."));
  REQUIRE(other.record.fixed_bytes() != L.fixed_bytes());
  CHECK(!other.record.check(rec).empty());
}

TEST_CASE("the resolved campaign reads back to itself, scene inline", "[campaign][resolved]") {
  const std::string root = TRUSS_SOURCE_DIR;
  for (const char* file : {"table1_dispersed.toml", "motor_torque.toml", "bay_count.toml"}) {
    INFO(file);
    const CampaignOptions c = truss::methods::parse_campaign_file(root + "/campaigns/" + file, {"output.history_runs=[1, 2]"});
    const std::string text = resolved_campaign_toml(c);
    const CampaignOptions back = truss::methods::parse_campaign_text(text, "resolved.toml", "/nonexistent");
    CHECK(resolved_campaign_toml(back) == text);
    CHECK(truss::io::resolved_scene_toml(back.base) == truss::io::resolved_scene_toml(c.base));
    CHECK(back.output.history_runs == std::vector<std::int64_t>{1, 2});
    REQUIRE(back.dispersions.size() == c.dispersions.size());
    for (std::size_t i = 0; i < c.dispersions.size(); ++i) {
      CHECK(back.dispersions[i].std == c.dispersions[i].std);
      CHECK(back.dispersions[i].values == c.dispersions[i].values);
    }
  }
}

TEST_CASE("an inline scene: applied after the file, errors at the campaign file's line", "[campaign][inline]") {
  const CampaignOptions c = truss::methods::parse_campaign_text("[ensemble]\nn_runs = 3\n[scene.mast]\nn_bays = 7\n[scene.drive]\nmode = \"motor\"\n",
                                                "inline.toml", ".");
  CHECK(c.base.mast.n_bays == 7);
  CHECK(c.base.drive.mode == truss::sim::DriveMode::motor);
  // --set takes base-scene keys as truss-sim does, with or without "scene.", after the file.
  const CampaignOptions s = truss::methods::parse_campaign_text("[scene.mast]\nn_bays = 7\n", "inline.toml", ".",
                                                {"mast.n_bays=9", "scene.drive.mode=torque", "ensemble.n_runs=5"});
  CHECK(s.base.mast.n_bays == 9);
  CHECK(s.base.drive.mode == truss::sim::DriveMode::torque);
  CHECK(s.ensemble.n_runs == 5);
  auto error = [](const std::string& text) {
    try {
      truss::methods::parse_campaign_text(text, "inline.toml", ".");
    } catch (const truss::io::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK_THAT(error("[ensemble]\nn_runs = 3\n[scene.mast]\nn_bays = 7\nstrut_mas_kg = 1.0\n"),
             Catch::StartsWith("error: inline.toml:5: unknown key 'mast.strut_mas_kg'"));
  CHECK_THAT(error("[ensemble]\nn_runs = 3\n[scene.mast]\nn_bays = 0\n"), Catch::StartsWith("error: inline.toml:4: mast.n_bays"));
  CHECK_THAT(error("[scene.masts]\nn_bays = 3\n"), Catch::StartsWith("error: inline.toml:1: unknown key 'scene.masts'"));
  CHECK_THAT(error("[output]\nhistory_runs = [3]\n[ensemble]\nn_runs = 3\n"),
             Catch::StartsWith("error: inline.toml:2: output.history_runs: run 3 does not exist"));
}
