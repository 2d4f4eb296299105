// The end of a campaign's report on stderr (parallel/progress.hpp): the verdict on invalid input.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "parallel/progress.hpp"

using namespace truss::parallel;

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
  CHECK_THAT(warning, Catch::Contains("warning: 1 of 300 runs are invalid input") &&
                          Catch::Contains("run 3:"));
  const auto [half, at_half] = verdict_of(150, 150);  // exactly half is not "most"
  CHECK(half);
  const auto [most, error] = verdict_of(1, 299);
  CHECK_FALSE(most);
  CHECK_THAT(error, Catch::Contains("error: 299 of 300 runs are invalid input") &&
                        Catch::Contains("run 3:") &&
                        Catch::Contains("[[dispersion]]"));
  // The P99.865 bound's run count, from its definition (1 - p^n >= 0.95), written out here.
  CHECK(calc_runs_needed_p99_865() == 2218);
  CHECK(1.0 - std::pow(0.99865, 2218.0) >= 0.95);
  CHECK(1.0 - std::pow(0.99865, 2217.0) < 0.95);
}

TEST_CASE("progress line of a method of rounds: stage and runs against the cap", "[campaign][progress]") {
  std::FILE* f = std::tmpfile();
  Progress p(750, 0, ProgressMode::lines, 0.0, f);  // a line at every update
  StatusCounts counts{};
  counts[static_cast<std::size_t>(truss::sim::RunStatus::ok)] = 744;
  p.update(744, [&] { return counts; });                     // plain: runs against the rounds so far
  p.set_stage("level 2 (margin <= 0.0013 m), Markov step 3 of 9", 5950);
  p.update(744, [&] { return counts; });                     // staged: runs against the cap
  p.set_stage("", 0);
  p.finish(750, counts);
  std::rewind(f);
  std::string text;
  for (int c; (c = std::fgetc(f)) != EOF;) text += static_cast<char>(c);
  std::fclose(f);
  CHECK_THAT(text, Catch::Contains("744/750 runs (99.2 %)"));
  CHECK_THAT(text, Catch::Contains("level 2 (margin <= 0.0013 m), Markov step 3 of 9: 744 runs so far of at most "
                                   "5950: 744 ok;") &&
                       Catch::Contains("at most"));
  CHECK_THAT(text, Catch::Contains("750/750 runs") && Catch::Contains("done in"));
}
