// test_option_docs.cpp — the reference of a campaign file's keys in docs/campaigns.md is the one the
// option tables make (campaign/option_docs.hpp): a key added, renamed or re-documented in a table
// and not on the page fails here. TRUSS_UPDATE_OPTION_DOCS=1 writes the made reference into the
// page instead (then review the diff). And every key the reference lists is one the parser reads.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>

#include "campaign/option_docs.hpp"
#include "campaign_fixtures.hpp"
#include "methods/method_table.hpp"

using namespace truss;

namespace {

const std::string kPage = TRUSS_SOURCE_DIR "/docs/campaigns.md";

std::string read_page() {
  std::ifstream in(kPage);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST_CASE("docs/campaigns.md lists every campaign key as the option tables define it", "[campaign][docs]") {
  const std::string made = campaign::make_option_reference(methods::builtin_methods());
  std::string page = read_page();
  const std::size_t begin = page.find(campaign::kOptionReferenceBegin), end = page.find(campaign::kOptionReferenceEnd);
  REQUIRE(begin != std::string::npos);
  REQUIRE(end != std::string::npos);
  const std::size_t from = begin + std::string(campaign::kOptionReferenceBegin).size() + 1;
  if (const char* update = std::getenv("TRUSS_UPDATE_OPTION_DOCS"); update && std::string(update) == "1") {
    page.replace(from, end - from, made);
    std::ofstream(kPage) << page;
  }
  CHECK(read_page().substr(from, end - from) == made);
}

TEST_CASE("each key of the reference is read by the parser", "[campaign][docs]") {
  // The reference's rows of [ensemble.subset] and [sweep]: every key named there, set alone by --set,
  // parses (a key the tables did not hold would be refused as unknown); the uniform step's
  // half-width with the proposal it belongs to.
  const std::string made = campaign::make_option_reference(methods::builtin_methods());
  const std::regex table(R"(\*\*`\[([a-z_.]+)\]`\*\*)"), row(R"(\n\| `([a-z_0-9]+)` \|)");
  std::vector<std::string> names;
  for (std::sregex_iterator t(made.begin(), made.end(), table), none; t != none; ++t) names.push_back((*t)[1]);
  CHECK(names == std::vector<std::string>{"campaign", "ensemble", "output", "scene", "failure", "ensemble.design",
                                          "ensemble.stop", "ensemble.subset", "ensemble.importance", "sweep"});
  const std::size_t subset = made.find("**`[ensemble.subset]`**");
  const std::string rows = made.substr(subset, made.find("**`[ensemble.importance]`**") - subset);
  std::vector<std::string> keys;
  for (std::sregex_iterator r(rows.begin(), rows.end(), row), none; r != none; ++r) keys.push_back((*r)[1]);
  CHECK(keys == std::vector<std::string>{"n_per_level", "p0", "max_levels", "proposal", "proposal_half_width",
                                         "interval_cov"});
  const std::string base = "[ensemble]\nmethod = \"subset\"\n[failure]\nmargin = \"motor_torque_margin_Nm\"\n"
                           "[[dispersion]]\nkey = \"drive.speed_m_per_s\"\ndistribution = \"normal\"\nstd = 0.05\n";
  const std::string values[] = {"2000", "0.1", "20", "adaptive_conditional", "1.0", "cov_interval"};
  for (std::size_t i = 0; i < keys.size(); ++i) {
    std::vector<std::string> sets{"ensemble.subset." + keys[i] + "=" + values[i]};
    if (keys[i] == "proposal_half_width") sets.insert(sets.begin(), "ensemble.subset.proposal=modified_metropolis");
    CHECK(campaign::test::campaign_error(base, "k.toml", sets).empty());
  }
  const std::size_t ce = made.find("**`[ensemble.importance]`**");
  const std::string ce_rows = made.substr(ce, made.find("**`[sweep]`**") - ce);
  keys.clear();
  for (std::sregex_iterator r(ce_rows.begin(), ce_rows.end(), row), none; r != none; ++r) keys.push_back((*r)[1]);
  CHECK(keys == std::vector<std::string>{"n_per_level", "n_final", "rho", "max_levels"});
  std::string ce_base = base;
  ce_base.replace(ce_base.find("subset"), 6, "importance");
  const std::string ce_values[] = {"1000", "2000", "0.1", "20"};
  for (std::size_t i = 0; i < keys.size(); ++i)
    CHECK(campaign::test::campaign_error(ce_base, "k.toml", {"ensemble.importance." + keys[i] + "=" + ce_values[i]})
              .empty());
}
