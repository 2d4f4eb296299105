// Scene TOML parsing and writing. See scene_toml.hpp.
#include "io/scene_toml.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>
#include <toml++/toml.h>

#include "io/suggest.hpp"
#include "sim/scene_keys.hpp"

namespace truss::io {
namespace {

using sim::SceneOptions;

// The key table lives in sim/scene_keys.hpp: this file parses and writes scenes through it.
using KeyDesc = sim::SceneKey;
using Kind = sim::KeyKind;
const std::vector<KeyDesc>& keys() { return sim::scene_keys(); }
const KeyDesc* find_key(std::string_view table, std::string_view key) { return sim::find_scene_key(table, key); }
bool is_table(std::string_view table) {
  for (const auto& d : keys())
    if (d.table == table) return true;
  return false;
}

// "Did you mean" suggestions over the key table: io/suggest.hpp.

// ---------------------------------------------------------------------------------------------
// Values.

// A TOML string literal for s (basic string, escaped).
std::string quote(std::string_view s) {
  std::string r = "\"";
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"': r += "\\\""; break;
      case '\\': r += "\\\\"; break;
      case '\n': r += "\\n"; break;
      case '\t': r += "\\t"; break;
      case '\r': r += "\\r"; break;
      default:
        if (c < 0x20 || c == 0x7f)
          r += fmt::format("\\u{:04X}", static_cast<unsigned>(c));
        else
          r += ch;
    }
  }
  return r + "\"";
}

std::string describe(const toml::node& v) {
  switch (v.type()) {
    case toml::node_type::string: {
      std::string s = *v.value<std::string>();
      if (s.size() > 40) s = s.substr(0, 37) + "...";
      return "a string " + quote(s);
    }
    case toml::node_type::integer: return fmt::format("an integer {}", *v.value<std::int64_t>());
    case toml::node_type::floating_point:
      return fmt::format("a floating-point number {}", toml_double(*v.value<double>()));
    case toml::node_type::boolean:
      return fmt::format("a boolean {}", *v.value<bool>() ? "true" : "false");
    case toml::node_type::array: return "an array";
    case toml::node_type::table: return "a table";
    case toml::node_type::date: return "a date";
    case toml::node_type::time: return "a time";
    case toml::node_type::date_time: return "a date-time";
    default: return "an unknown value";
  }
}

std::string allowed_text(const std::vector<std::string_view>& allowed) {
  std::string s;
  for (auto a : allowed) s += fmt::format("{}{}", s.empty() ? "" : ", ", quote(a));
  return s;
}

// Sets one key from a TOML value. Returns "" on success, else the reason, starting with the
// dotted key name.
std::string apply_value(SceneOptions& s, const KeyDesc& d, const toml::node& v) {
  const std::string name = d.dotted();
  switch (d.kind) {
    case Kind::real:
    case Kind::opt_real: {
      if (auto f = v.value_exact<double>()) {
        d.set_real(s, *f);
        return {};
      }
      if (auto i = v.value_exact<std::int64_t>()) {
        d.set_real(s, static_cast<double>(*i));
        return {};
      }
      return fmt::format("{}: expected a number (float or integer), got {}", name, describe(v));
    }
    case Kind::integer: {
      if (auto i = v.value_exact<std::int64_t>()) {
        if (*i < d.int_min || *i > d.int_max)
          return fmt::format("{}: integer {} is out of range [{}, {}]", name, *i, d.int_min,
                             d.int_max);
        d.set_int(s, *i);
        return {};
      }
      return fmt::format("{}: expected an integer, got {}", name, describe(v));
    }
    case Kind::enumeration: {
      // A yes/no key (allowed values "false", "true") takes the TOML booleans.
      const bool yes_no = d.allowed.size() == 2 && d.allowed[0] == "false" && d.allowed[1] == "true";
      if (auto b = v.value_exact<bool>(); b && yes_no) {
        d.set_enum(s, *b ? 1 : 0);
        return {};
      }
      if (auto str = v.value_exact<std::string>(); str && !yes_no) {
        for (std::size_t i = 0; i < d.allowed.size(); ++i) {
          if (d.allowed[i] == *str) {
            d.set_enum(s, i);
            return {};
          }
        }
        std::string msg = fmt::format("{}: unknown value {}; allowed values: {}", name,
                                      quote(*str), allowed_text(d.allowed));
        if (auto sug = suggest_value(*str, d.allowed)) msg += fmt::format(" (did you mean {}?)", quote(*sug));
        return msg;
      }
      if (yes_no) return fmt::format("{}: expected true or false, got {}", name, describe(v));
      return fmt::format("{}: expected a string, one of {}; got {}", name, allowed_text(d.allowed),
                         describe(v));
    }
  }
  return fmt::format("{}: internal error: unknown key kind", name);
}

// ---------------------------------------------------------------------------------------------
// Parsing.

struct Diag {
  std::size_t order_major;  // file line, or a large number + override index for --set
  std::size_t order_minor;  // column
  std::string text;         // complete message line
};

// Where the value of a key came from, for validate() messages.
struct Origin {
  std::size_t line = 0;     // > 0: the key's line in the file
  std::string set_text;     // non-empty: the --set argument that set it last
  std::string where;        // non-empty: FILE:LINE of a setting from another file (a campaign)
};

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(b, e - b + 1));
}

std::string unknown_key_text(std::string_view table, std::string_view key) {
  const auto sug = suggest_key(table, key);
  if (table.empty()) {
    if (sug) return fmt::format("unknown key '{}' at the top level (did you mean '{}'?)", key, *sug);
    return fmt::format("unknown key '{}' at the top level; keys belong in a table: {}", key,
                       known_tables_text());
  }
  if (sug) return fmt::format("unknown key '{}.{}' (did you mean '{}'?)", table, key, *sug);
  return fmt::format("unknown key '{}.{}'; known keys in [{}]: {}", table, key, table,
                     known_keys_text(table));
}

std::string unknown_table_text(std::string_view table) {
  std::string msg = fmt::format("unknown table [{}]", table);
  if (auto sug = suggest_table(table))
    msg += fmt::format(" (did you mean [{}]?)", *sug);
  else
    msg += fmt::format("; known tables: {}", known_tables_text());
  return msg;
}

void parse_table_contents(SceneOptions& s, const std::string& source, std::string_view tname,
                          const toml::table& tbl, std::vector<Diag>& diags,
                          std::map<std::string, Origin>& origins) {
  for (auto&& [k, v] : tbl) {
    const std::size_t line = v.source().begin.line ? v.source().begin.line : k.source().begin.line;
    const std::size_t col = v.source().begin.column;
    const KeyDesc* d = find_key(tname, k.str());
    if (!d) {
      diags.push_back({line, col,
                       fmt::format("error: {}:{}: {}", source, line, unknown_key_text(tname, k.str()))});
      continue;
    }
    const std::string err = apply_value(s, *d, v);
    if (!err.empty()) {
      diags.push_back({line, col, fmt::format("error: {}:{}: {}", source, line, err)});
      continue;
    }
    origins[d->dotted()] = Origin{line, {}, {}};
  }
}

void apply_override(SceneOptions& s, const SceneSetting& setting, std::size_t index,
                    std::vector<Diag>& diags, std::map<std::string, Origin>& origins) {
  const std::string& arg = setting.assignment;
  const std::size_t order = std::numeric_limits<std::size_t>::max() / 2 + index;
  auto fail = [&](const std::string& why) {
    if (setting.where.empty()) diags.push_back({order, 0, fmt::format("error: --set {}: {}", arg, why)});
    else diags.push_back({order, 0, fmt::format("error: {}: {}", setting.where, why)});
  };
  const auto eq = arg.find('=');
  if (eq == std::string::npos) return fail("expected table.key=value (e.g. --set mast.n_bays=12)");
  const std::string key = trim(std::string_view(arg).substr(0, eq));
  const std::string value = trim(std::string_view(arg).substr(eq + 1));
  const auto dot = key.find('.');
  if (key.empty()) return fail("missing key before '='");
  if (dot == std::string::npos) {
    if (is_table(key)) return fail(fmt::format("'{}' is a table; give table.key=value", key));
    return fail(unknown_key_text("", key));
  }
  const std::string tname = key.substr(0, dot);
  const std::string kname = key.substr(dot + 1);
  if (!is_table(tname)) return fail(unknown_table_text(tname));
  const KeyDesc* d = find_key(tname, kname);
  if (!d) return fail(unknown_key_text(tname, kname));
  if (value.empty()) return fail(fmt::format("{}: missing value after '='", key));

  // The value is read as a TOML value; anything that is not one (a bare word such as motor) is
  // taken as a string.
  std::optional<toml::table> parsed;
  try {
    const std::string doc = "v = " + value + "\n";
    parsed = toml::parse(std::string_view(doc), std::string_view("--set"));
  } catch (const toml::parse_error&) {
    parsed.reset();
  }
  const toml::node* node = nullptr;
  toml::value<std::string> as_string{value};
  if (parsed && parsed->size() == 1 && parsed->contains("v"))
    node = parsed->get("v");
  else
    node = &as_string;
  const std::string err = apply_value(s, *d, *node);
  if (!err.empty()) return fail(err);
  origins[d->dotted()] = setting.where.empty() ? Origin{0, arg, {}} : Origin{0, {}, setting.where};
}

std::string join_diags(std::vector<Diag> diags) {
  std::stable_sort(diags.begin(), diags.end(), [](const Diag& a, const Diag& b) {
    return std::tie(a.order_major, a.order_minor) < std::tie(b.order_major, b.order_minor);
  });
  std::string msg;
  for (const auto& d : diags) {
    if (!msg.empty()) msg += '\n';
    msg += d.text;
  }
  return msg;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

namespace {

// Where a key's value came from, for messages: "FILE:LINE", "--set ARG", a campaign's FILE:LINE,
// or "default".
std::string origin_text(const std::map<std::string, Origin>& origins, const std::string& key, const std::string& source) {
  const auto it = origins.find(key);
  if (it == origins.end()) return "default";
  if (it->second.line > 0) return fmt::format("{}:{}", source, it->second.line);
  if (!it->second.set_text.empty()) return "--set " + it->second.set_text;
  return it->second.where.empty() ? "default" : it->second.where;
}

// The keys a geometry error of validate_mast involves, from the start of its message.
std::vector<std::string> geometry_keys(const std::string& msg) {
  if (msg.rfind("rail:", 0) == 0 || msg.rfind("rail geometry:", 0) == 0)
    return {"rail.x_m", "rail.y_m", "rail.beta_deg", "mast.strut_length_m"};
  if (msg.rfind("panels.", 0) == 0)
    return {"panels.count", "panels.length_m", "panels.tip_height_m", "mast.n_bays", "mast.strut_length_m", "rail.x_m",
            "rail.y_m", "rail.beta_deg"};
  return {};
}

// validate() (with the hard ranges of the key table), then the mast's geometry, then the
// plausibility warnings (typical ranges) of the keys the user set.
void check_scene(const SceneOptions& s, const std::string& source_name, const std::map<std::string, Origin>& origins,
                 std::vector<std::string>* warnings) {
  std::string bad = s.validate();
  if (!bad.empty()) {
    // validate() names the key first: "table.key: reason".
    const std::string key = bad.substr(0, bad.find(':'));
    const auto it = origins.find(key);
    if (it != origins.end() && it->second.line > 0)
      throw InputError(fmt::format("error: {}:{}: {}", source_name, it->second.line, bad));
    if (it != origins.end() && !it->second.set_text.empty())
      throw InputError(
          fmt::format("error: {}: {} (set by --set {})", source_name, bad, it->second.set_text));
    if (it != origins.end() && !it->second.where.empty()) throw InputError(fmt::format("error: {}: {}", it->second.where, bad));
    throw InputError(fmt::format("error: {}: {}", source_name, bad));
  }
  bad = sim::validate_mast(sim::build_mast(s), s);
  if (!bad.empty()) {
    std::string involved;
    for (const auto& k : geometry_keys(bad)) {
      const KeyDesc* d = sim::find_scene_key(k);
      const auto v = d ? sim::key_value(*d, s) : std::nullopt;
      const std::string unit = d && d->unit != "1" ? fmt::format(" {}", d->unit) : "";
      involved += fmt::format("\n  {} = {}{} ({})", k, v ? fmt::format("{}", *v) : "unset", unit,
                              origin_text(origins, k, source_name));
    }
    throw InputError(fmt::format("error: {}: {}{}", source_name, bad, involved.empty() ? "" : "\n  keys involved:" + involved));
  }
  if (!warnings) return;
  for (const auto& [key, origin] : origins) {
    const KeyDesc* d = sim::find_scene_key(key);
    const auto v = d ? sim::key_value(*d, s) : std::nullopt;
    if (!v) continue;
    if (const std::string w = sim::check_typical_range(*d, *v); !w.empty())
      warnings->push_back(fmt::format("warning: {}: {}", origin_text(origins, key, source_name), w));
  }
}

sim::SceneOptions parse_scene(std::string_view text, const std::string& source_name,
                              const std::vector<SceneSetting>& overrides, bool validate,
                              std::vector<std::string>* warnings = nullptr) {
  toml::table root;
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    const auto& b = e.source().begin;
    throw InputError(fmt::format("error: {}:{}:{}: TOML syntax error: {}", source_name, b.line,
                                 b.column, e.description()));
  }

  SceneOptions s;
  std::vector<Diag> diags;
  std::map<std::string, Origin> origins;
  for (auto&& [k, v] : root) {
    const std::string tname(k.str());
    const std::size_t line = k.source().begin.line ? k.source().begin.line : v.source().begin.line;
    const std::size_t col = k.source().begin.column;
    if (!is_table(tname)) {
      const std::string why = v.is_table() ? unknown_table_text(tname) : unknown_key_text("", tname);
      diags.push_back({line, col, fmt::format("error: {}:{}: {}", source_name, line, why)});
      continue;
    }
    const toml::table* tbl = v.as_table();
    if (!tbl) {
      diags.push_back({line, col,
                       fmt::format("error: {}:{}: {}: expected a table ([{}]), got {}", source_name,
                                   line, tname, tname, describe(v))});
      continue;
    }
    parse_table_contents(s, source_name, tname, *tbl, diags, origins);
  }
  for (std::size_t i = 0; i < overrides.size(); ++i) apply_override(s, overrides[i], i, diags, origins);
  if (!diags.empty()) throw InputError(join_diags(std::move(diags)));
  if (!validate) return s;
  check_scene(s, source_name, origins, warnings);
  return s;
}

}  // namespace

namespace {
std::vector<SceneSetting> as_settings(const std::vector<std::string>& overrides) {
  std::vector<SceneSetting> v;
  for (const auto& o : overrides) v.push_back({o, {}});
  return v;
}
}  // namespace

sim::SceneOptions parse_scene_text(std::string_view text, const std::string& source_name,
                                   const std::vector<std::string>& overrides) {
  return parse_scene(text, source_name, as_settings(overrides), true);
}

sim::SceneOptions parse_scene_text_with(std::string_view text, const std::string& source_name,
                                        const std::vector<SceneSetting>& settings, std::vector<std::string>* warnings) {
  return parse_scene(text, source_name, settings, true, warnings);
}

sim::SceneOptions parse_scene_variant(const sim::SceneOptions& base, std::string_view text,
                                      const std::string& source_name,
                                      const std::vector<SceneSetting>& settings, const std::vector<SceneSetting>& more,
                                      std::vector<std::string>* warnings) {
  SceneOptions s = base;
  std::vector<Diag> diags;
  std::map<std::string, Origin> origins;
  for (std::size_t i = 0; i < more.size(); ++i) apply_override(s, more[i], settings.size() + i, diags, origins);
  if (diags.empty()) {
    try {
      check_scene(s, source_name, origins, warnings);
      return s;
    } catch (const InputError&) {
      // worded below as the whole text gives it (a key of the file is named with its line there)
    }
  }
  std::vector<SceneSetting> all = settings;
  all.insert(all.end(), more.begin(), more.end());
  return parse_scene(text, source_name, all, true);  // throws the InputError
}

sim::SceneOptions parse_scene_text_unvalidated(std::string_view text,
                                               const std::string& source_name,
                                               const std::vector<std::string>& overrides) {
  return parse_scene(text, source_name, as_settings(overrides), false);
}

sim::SceneOptions parse_scene_file(const std::string& path, const std::vector<std::string>& overrides,
                                   std::vector<std::string>* warnings) {
  return parse_scene_file_with(path, as_settings(overrides), warnings);
}

sim::SceneOptions parse_scene_file_with(const std::string& path, const std::vector<SceneSetting>& overrides,
                                        std::vector<std::string>* warnings) {
  return parse_scene(read_input_file(path, "scene file"), path, overrides, true, warnings);
}

std::string toml_string(std::string_view s) { return quote(s); }

std::string toml_double(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::string s = fmt::format("{}", v);  // shortest round-trip representation
  if (s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

std::vector<std::string> known_scene_keys() {
  std::vector<std::string> r;
  for (const auto& d : keys()) r.push_back(d.dotted());
  return r;
}

std::string resolved_scene_toml(const sim::SceneOptions& s) {
  std::string out =
      "# Resolved scene: every key with the value used, defaults included.\n"
      "# Units are in the key names; see campaigns/scenes/table1.toml for the meaning of each.\n";
  std::string_view current;
  for (const auto& d : keys()) {
    if (d.table != current) {
      out += fmt::format("\n[{}]\n", d.table);
      current = d.table;
    }
    std::string value;
    switch (d.kind) {
      case Kind::real: value = toml_double(d.get_real(s)); break;
      case Kind::opt_real:
        if (auto v = d.get_opt(s)) value = toml_double(*v);
        break;
      case Kind::integer: value = fmt::format("{}", d.get_int(s)); break;
      case Kind::enumeration: {
        const std::size_t i = d.get_enum(s);
        value = i < d.allowed.size() ? quote(d.allowed[i]) : quote(fmt::format("<bad enum {}>", i));
        if (d.allowed.size() == 2 && d.allowed[0] == "false" && d.allowed[1] == "true") value = i == 1 ? "true" : "false";
        break;
      }
    }
    std::string line = value.empty() ? fmt::format("# {} unset", d.key)
                                     : fmt::format("{} = {}", d.key, value);
    if (line.size() < 40) line.resize(40, ' ');
    out += fmt::format("{}  # {}\n", line, d.comment);
  }
  return out;
}

}  // namespace truss::io
