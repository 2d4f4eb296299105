// Reading campaign TOML (campaign.cpp, campaign_method.cpp): where a value came from (file:line or
// the --set that gave it) and typed getters that fail with it. Internal to the campaign parser.
#pragma once
#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "campaign/campaign.hpp"
#include "io/scene_toml.hpp"

namespace truss::campaign::detail {

struct Ctx {
  std::string file;
  std::map<const toml::node*, std::string> set_by;  // values put in the tree by --set: the argument
  [[noreturn]] void fail(const toml::node* at, const std::string& what) const {
    if (const auto it = set_by.find(at); it != set_by.end())
      throw io::InputError(fmt::format("error: --set {}: {}", it->second, what));
    if (at && at->source().begin.line > 0)
      throw io::InputError(fmt::format("error: {}:{}: {}", file, at->source().begin.line, what));
    throw io::InputError(fmt::format("error: {}: {}", file, what));
  }
};

inline std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "\"" : ", \"") + x + "\"";
  return s;
}

inline double get_number(const Ctx& c, const toml::node& n, const std::string& key) {
  if (auto i = n.value_exact<std::int64_t>()) return static_cast<double>(*i);
  if (auto d = n.value_exact<double>()) return *d;
  c.fail(&n, fmt::format("{}: expected a number", key));
}

inline std::int64_t get_integer(const Ctx& c, const toml::node& n, const std::string& key) {
  auto i = n.value_exact<std::int64_t>();
  if (!i) c.fail(&n, key + ": expected an integer");
  return *i;
}

inline std::string get_string(const Ctx& c, const toml::node& n, const std::string& key,
                              const std::vector<std::string>& allowed = {}) {
  auto s = n.value_exact<std::string>();
  if (!s) c.fail(&n, fmt::format("{}: expected a string", key));
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), *s) == allowed.end())
    c.fail(&n, fmt::format("{}: \"{}\" is not one of {}", key, *s, join(allowed)));
  return *s;
}

// campaign_method.cpp: [ensemble.subset] and [failure] into the options; the subset's run cap as
// ensemble.n_runs (refusing an n_runs written with method = "subset"); the rules of the method.
void parse_subset_table(const Ctx& c, const toml::table& t, CampaignOptions& o);
void parse_failure_table(const Ctx& c, const toml::table& t, CampaignOptions& o);
void parse_stop_table(const Ctx& c, const toml::table& t, CampaignOptions& o);
void derive_subset_runs(const Ctx& c, const toml::table& root, CampaignOptions& o);
std::string validate_method(const CampaignOptions& o);
std::string method_toml(const CampaignOptions& o);  // [ensemble] method, [ensemble.subset], [failure]
// sweep.cpp: [sweep] into o.sweep (its rules: validate_sweep).
void parse_sweep_table(const Ctx& c, const toml::table& t, CampaignOptions& o);
}  // namespace truss::campaign::detail
