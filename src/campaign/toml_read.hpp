// Reading campaign TOML (campaign.cpp, campaign_method.cpp, and each method's parser of its own
// tables, methods/): where a value came from (file:line or the --set that gave it) and typed
// getters that fail with it.
#pragma once
#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "campaign/campaign.hpp"
#include "campaign/failure.hpp"
#include "io/scene_toml.hpp"
#include "io/suggest.hpp"

namespace truss::campaign::detail {

struct Ctx {
  std::string file;
  std::map<const toml::node*, std::string> set_by;  // values put in the tree by --set: the argument
  const MethodCatalog* methods = nullptr;           // the rows ensemble.method names
  [[noreturn]] void fail(const toml::node* at, const std::string& what) const {
    if (const auto it = set_by.find(at); it != set_by.end())
      throw io::InputError(fmt::format("error: --set {}: {}", it->second, what));
    if (at && at->source().begin.line > 0)
      throw io::InputError(fmt::format("error: {}:{}: {}", file, at->source().begin.line, what));
    throw io::InputError(fmt::format("error: {}: {}", file, what));
  }
};

// "; did you mean ensemble.n_runs?" when a name of `known` (a message's list, "a, b, [c.d]": a
// name without a dot lies in the typed key's table) is close to `typed` as io::suggest_value
// judges closeness (the scene keys' rule); "" otherwise.
inline std::string did_you_mean(const std::string& typed, std::string_view known) {
  const std::size_t dot = typed.rfind('.');
  const std::string table = dot == std::string::npos ? "" : typed.substr(0, dot + 1);
  std::vector<std::string> full, last;
  for (std::size_t start = 0; start < known.size();) {
    std::size_t end = known.find(',', start);
    if (end == std::string_view::npos) end = known.size();
    std::string name(known.substr(start, end - start));
    name = name.substr(name.find_last_of(' ') == std::string::npos ? 0 : name.find_last_of(' ') + 1);
    std::erase_if(name, [](char ch) { return ch == '[' || ch == ']'; });
    if (!name.empty()) {
      full.push_back(name.find('.') == std::string::npos ? table + name : name);
      last.push_back(full.back().substr(full.back().rfind('.') + 1));
    }
    start = end + 1;
  }
  const std::vector<std::string_view> views(last.begin(), last.end());
  const auto best = io::suggest_value(dot == std::string::npos ? typed : typed.substr(dot + 1), views);
  if (!best) return {};
  const auto at = static_cast<std::size_t>(std::find(last.begin(), last.end(), *best) - last.begin());
  return fmt::format("; did you mean {}?", full[at]);
}

// "unknown key 'KEY'; did you mean ...? (known: KNOWN)".
inline std::string unknown_key_text(const std::string& key, std::string_view known) {
  return fmt::format("unknown key '{}'{} (known: {})", key, did_you_mean(key, known), known);
}
}  // namespace truss::campaign::detail

namespace truss::campaign {

// What a method's row reads (method_options.hpp): the campaign's tree, its own table and where
// messages point.
struct MethodInput {
  const detail::Ctx& ctx;      // file and --set of each value (the getters below); ctx.methods
  const toml::table& root;     // the campaign file (the row's root tables, e.g. [failure])
  const toml::table* table;    // [ensemble.<name>], or null: the defaults
  std::string prefix;          // "ensemble.<name>.": the keys' names in messages
};

}  // namespace truss::campaign

namespace truss::campaign::detail {

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

// campaign_method.cpp: ensemble.method and the method's own tables (method_options.hpp).
std::vector<std::string> method_names(const Ctx& c);
// [ensemble.<row>]: a table, or false (none).
void check_method_key(const Ctx& c, const std::string& key, const toml::node& v);
// A root table that a row of the catalog reads ([failure]).
bool is_method_table(const Ctx& c, std::string_view root_table);
// The root tables the rows of the catalog read, each once, in table order.
std::vector<std::string> method_root_tables(const Ctx& c);
// The chosen row reads its tables into o.ensemble.method; a run count it chooses is n_runs.
void parse_method(const Ctx& c, const toml::table& root, CampaignOptions& o);
// failure.cpp: [failure] into f (failure.hpp), for the rows that read it.
void parse_failure_table(const Ctx& c, const toml::table& t, FailureOptions& f);
// A row that reads [failure] only as a design sweep's event (design, stop): [failure] of root into
// f when root has a [sweep]; without one, [failure] is refused (subset simulation reads it).
void parse_sweep_failure(const Ctx& c, const toml::table& root, FailureOptions& f);
// sweep.cpp: [sweep] into o.sweep (its rules: validate_sweep).
void parse_sweep_table(const Ctx& c, const toml::table& t, CampaignOptions& o);
}  // namespace truss::campaign::detail
