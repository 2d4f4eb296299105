// The campaign engine without MPI: run records and their bytes, statistics against hand-computed
// order statistics, the Saltelli design with one factor per dispersion, and the resolved campaign
// text (the journal's tests are in test_journal.cpp).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "campaign/campaign.hpp"
#include "campaign/progress.hpp"
#include "campaign/results.hpp"
#include "campaign/run_record.hpp"
#include "io/scene_toml.hpp"
#include "campaign_fixtures.hpp"

using namespace truss::campaign;
using truss::campaign::test::small_campaign;

namespace {

std::string bytes_of(RunRecord r) {
  r.wall_time_s = 0.0;
  std::string s;
  r.append_bytes(s);
  return s;
}

}  // namespace

TEST_CASE("a run record is a pure function of (campaign, run index) and survives its bytes", "[campaign][record]") {
  const CampaignContext ctx(small_campaign());
  const RunRecord a = calc_run_record(ctx, 5, 0);
  const RunRecord b = calc_run_record(ctx, 5, 3);
  REQUIRE(a.status == truss::sim::RunStatus::ok);
  CHECK(a.inputs.size() == 5 + 6 + 1);        // per bay, per frame (n + 1), per run
  CHECK(bytes_of(a).size() == bytes_of(b).size());
  RunRecord b0 = b;
  b0.rank = 0;
  CHECK(bytes_of(a) == bytes_of(b0));          // only rank and wall time depend on where it ran
  std::string bytes;
  a.append_bytes(bytes);
  const RunRecord c = RunRecord::from_bytes(bytes, ctx.columns);
  CHECK(bytes_of(c) == bytes_of(a));
  CHECK(c.wall_time_s == a.wall_time_s);
  CHECK_THROWS_AS(RunRecord::from_bytes(std::string_view(bytes).substr(0, bytes.size() - 1), ctx.columns), std::runtime_error);
  // Different runs draw different inputs.
  CHECK(calc_run_record(ctx, 6, 0).inputs != a.inputs);
}

TEST_CASE("statistics: ok runs with finite values, numpy's linear percentiles", "[campaign][stats]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Sorted 1, 2, 4, 10 (ok and finite); the 100 is a failed run, the NaN an ok run without value.
  const std::vector<double> v = {4.0, 100.0, 1.0, nan, 10.0, 2.0};
  const std::vector<std::uint8_t> ok = {1, 0, 1, 1, 1, 1};
  const Stats s = calc_stats(v, ok);
  CHECK(s.count == 4);
  CHECK(s.min == 1.0);
  CHECK(s.max == 10.0);
  CHECK(s.mean == 4.25);
  CHECK(s.std == Approx(std::sqrt((3.25 * 3.25 + 2.25 * 2.25 + 0.25 * 0.25 + 5.75 * 5.75) / 3.0)).epsilon(1e-15));
  // Index h = q/100 * 3. p50: h = 1.5 -> 2 + 0.5 * 2 = 3. p5: h = 0.15 -> 1 + 0.15. p99.865:
  // h = 2.99595, lerp from the upper end: 10 - 6 * (1 - 0.99595).
  CHECK(s.percentiles[2] == 3.0);
  CHECK(s.percentiles[1] == Approx(1.15).epsilon(1e-15));
  CHECK(s.percentiles[5] == Approx(10.0 - 6.0 * (1.0 - 0.99595)).epsilon(1e-15));
  const std::vector<double> sorted = {1, 2, 4, 10};
  CHECK(calc_percentile_sorted(sorted, 0.0) == 1.0);
  CHECK(calc_percentile_sorted(sorted, 100.0) == 10.0);
  const Stats none = calc_stats({nan, 3.0}, {1, 0});
  CHECK(none.count == 0);
  CHECK(std::isnan(none.mean));
  CHECK(std::isnan(none.percentiles[0]));
  CHECK(std::isnan(calc_stats({3.0}, {1}).std));  // one value: no sample deviation
}

TEST_CASE("statistics of large columns: the order statistics of a full sort", "[campaign][stats]") {
  // Above 16,384 values calc_stats selects by bucketing: compare with std::sort and the same
  // interpolation formula (exact equality: the same two order statistics, the same arithmetic).
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(1.25, 0.01);
  const std::size_t n = 50000;
  std::vector<std::vector<double>> columns(4, std::vector<double>(n));
  for (std::size_t i = 0; i < n; ++i) {
    columns[0][i] = g(rng);                                        // a load: narrow spread
    columns[1][i] = static_cast<double>(rng() % 3) - 1.0;          // heavy ties: -1, 0, 1
    columns[2][i] = i == 17 ? 1e300 : -g(rng) * 1e-6;              // one far outlier: nearly all in one bucket
    columns[3][i] = (rng() % 2 ? 1.0 : -1.0) * std::exp(10 * g(rng));  // both signs, wide range
  }
  const std::vector<std::uint8_t> use(n, 1);
  for (const auto& c : columns) {
    const Stats st = calc_stats(c, use);
    std::vector<double> sorted = c;
    std::sort(sorted.begin(), sorted.end());
    CHECK(st.min == sorted.front());
    CHECK(st.max == sorted.back());
    for (std::size_t k = 0; k < kStatPercentiles.size(); ++k) CHECK(st.percentiles[k] == calc_percentile_sorted(sorted, kStatPercentiles[k]));
  }
}

TEST_CASE("Saltelli design: AB_g takes every dimension of dispersion g from B", "[campaign][saltelli]") {
  const CampaignOptions c = small_campaign("saltelli", 5 * 8);
  REQUIRE(saltelli_block_runs(c) == 5);
  const RunSampler s(c);
  const DimensionLayout& L = s.layout();
  const auto d = static_cast<std::size_t>(L.total);
  for (std::int64_t block = 0; block < 8; ++block) {
    std::vector<std::vector<double>> u(5, std::vector<double>(d));
    for (int k = 0; k < 5; ++k) s.calc_uniforms(block * 5 + k, u[static_cast<std::size_t>(k)].data());
    for (int g = 0; g < 3; ++g)
      for (std::size_t j = 0; j < d; ++j) {
        const bool in_g = static_cast<int>(j) >= L.offset[static_cast<std::size_t>(g)] &&
                          static_cast<int>(j) < L.offset[static_cast<std::size_t>(g)] + L.count[static_cast<std::size_t>(g)];
        CHECK(u[static_cast<std::size_t>(2 + g)][j] == (in_g ? u[1][j] : u[0][j]));
        CHECK((u[0][j] > 0.0 && u[0][j] < 1.0));
      }
    CHECK(u[0] != u[1]);
  }
  // Every block has its own A and B.
  std::vector<double> a0(d), a1(d);
  s.calc_uniforms(0, a0.data());
  s.calc_uniforms(5, a1.data());
  CHECK(a0 != a1);
  // A run count that is not whole blocks is a campaign error naming ensemble.n_runs.
  try {
    small_campaign("saltelli", 42);
    FAIL("no error");
  } catch (const truss::io::InputError& e) {
    CHECK_THAT(e.what(), Catch::Contains("ensemble.n_runs") && Catch::Contains("multiple of 5"));
  }
}

TEST_CASE("a ResultTable refuses a run twice or out of range", "[campaign][results]") {
  const CampaignContext ctx(small_campaign());
  ResultTable t(ctx.options.ensemble.n_runs, ctx.columns);
  t.add(calc_run_record(ctx, 3, 0), 0);
  CHECK(t.has(3));
  CHECK(!t.has(2));
  CHECK(t.n_done() == 1);
  CHECK_THROWS_AS(t.add(calc_run_record(ctx, 3, 1), 0), std::runtime_error);
  RunRecord r = calc_run_record(ctx, 4, 0);
  r.run_index = 24;
  CHECK_THROWS_AS(t.add(r, 0), std::runtime_error);
}

TEST_CASE("the resolved campaign reads back to itself, scene inline", "[campaign][resolved]") {
  const std::string root = TRUSS_SOURCE_DIR;
  for (const char* file : {"table1_dispersed.toml", "motor_torque.toml", "bay_count.toml"}) {
    INFO(file);
    const CampaignOptions c = parse_campaign_file(root + "/campaigns/" + file, {"output.history_runs=[1, 2]"});
    const std::string text = resolved_campaign_toml(c);
    const CampaignOptions back = parse_campaign_text(text, "resolved.toml", "/nonexistent");
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
  const CampaignOptions c = parse_campaign_text("[ensemble]\nn_runs = 3\n[scene.mast]\nn_bays = 7\n[scene.drive]\nmode = \"motor\"\n",
                                                "inline.toml", ".");
  CHECK(c.base.mast.n_bays == 7);
  CHECK(c.base.drive.mode == truss::sim::DriveMode::motor);
  // --set takes base-scene keys as truss-sim does, with or without "scene.", after the file.
  const CampaignOptions s = parse_campaign_text("[scene.mast]\nn_bays = 7\n", "inline.toml", ".",
                                                {"mast.n_bays=9", "scene.drive.mode=torque", "ensemble.n_runs=5"});
  CHECK(s.base.mast.n_bays == 9);
  CHECK(s.base.drive.mode == truss::sim::DriveMode::torque);
  CHECK(s.ensemble.n_runs == 5);
  auto error = [](const std::string& text) {
    try {
      parse_campaign_text(text, "inline.toml", ".");
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

namespace {
// What print_campaign_verdict prints for these counts, and whether the runs are usable.
std::pair<bool, std::string> verdict_of(std::int64_t ok, std::int64_t invalid) {
  StatusCounts counts{};
  counts[static_cast<std::size_t>(truss::sim::RunStatus::ok)] = ok;
  counts[static_cast<std::size_t>(truss::sim::RunStatus::invalid_input)] = invalid;
  std::FILE* f = std::tmpfile();
  const bool usable = print_campaign_verdict(f, counts, "run 3: mast.strut_mass_kg: bay 1 has a non-positive strut mass");
  std::rewind(f);
  std::string text;
  for (int c; (c = std::fgetc(f)) != EOF;) text += static_cast<char>(c);
  std::fclose(f);
  return {usable, text};
}
}  // namespace

TEST_CASE("end of a campaign: mostly invalid input is an error, some a warning", "[campaign][verdict]") {
  const auto [all_ok, quiet] = verdict_of(300, 0);
  CHECK(all_ok);
  CHECK(quiet.empty());
  const auto [usable, warning] = verdict_of(299, 1);
  CHECK(usable);
  CHECK_THAT(warning, Catch::Contains("warning: 1 of 300 runs are invalid input") && Catch::Contains("run 3:"));
  const auto [half, at_half] = verdict_of(150, 150);  // exactly half is not "most"
  CHECK(half);
  const auto [most, error] = verdict_of(1, 299);
  CHECK_FALSE(most);
  CHECK_THAT(error, Catch::Contains("error: 299 of 300 runs are invalid input") && Catch::Contains("run 3:") &&
                        Catch::Contains("[[dispersion]]"));
  // The P99.865 bound's run count, from its definition (1 - p^n >= 0.95), written out here.
  CHECK(calc_runs_needed_p99_865() == 2218);
  CHECK(1.0 - std::pow(0.99865, 2218.0) >= 0.95);
  CHECK(1.0 - std::pow(0.99865, 2217.0) < 0.95);
}
