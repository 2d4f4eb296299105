// The option tables' reader, messages and values (option_table.hpp).
#include "campaign/option_table.hpp"

#include <algorithm>
#include <sstream>

#include <fmt/format.h>

#include "campaign/method_options.hpp"
#include "io/suggest.hpp"

namespace truss::campaign {

void TomlSource::fail(const toml::node* at, const std::string& what) const {
  if (const auto it = set_by.find(at); it != set_by.end())
    throw io::InputError(fmt::format("error: --set {}: {}", it->second, what));
  if (at && at->source().begin.line > 0)
    throw io::InputError(fmt::format("error: {}:{}: {}", file, at->source().begin.line, what));
  throw io::InputError(fmt::format("error: {}: {}", file, what));
}

std::string OptionRange::text() const {
  if (std::isfinite(lo) && std::isfinite(hi))
    return fmt::format("{}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
  if (std::isfinite(lo)) return fmt::format("{} {}", lo_open ? ">" : ">=", lo);
  if (std::isfinite(hi)) return fmt::format("{} {}", hi_open ? "<" : "<=", hi);
  return {};
}

std::string check_option_range(const OptionSpec& spec, const std::string& key, double v) {
  if (!spec.range.is_bounded() || spec.range.contains(v)) return {};
  const std::string unit = spec.unit.empty() || spec.unit == "1" ? std::string() : fmt::format(" {}", spec.unit);
  const bool interval = std::isfinite(spec.range.lo) && std::isfinite(spec.range.hi);
  return fmt::format("{}: must {} {}{}, got {}", key, interval ? "lie in" : "be", spec.range.text(), unit, v);
}

namespace {

std::string quoted_list(const std::vector<std::string_view>& names) {
  std::string s;
  for (std::string_view n : names) s += fmt::format("{}\"{}\"", s.empty() ? "" : ", ", n);
  return s;
}

double read_real(const TomlSource& src, const toml::node& n, const std::string& key) {
  if (auto i = n.value_exact<std::int64_t>()) return static_cast<double>(*i);
  if (auto d = n.value_exact<double>()) return *d;
  src.fail(&n, fmt::format("{}: expected a number", key));
}

std::int64_t read_integer(const TomlSource& src, const toml::node& n, const std::string& key) {
  const auto i = n.value_exact<std::int64_t>();
  if (!i) src.fail(&n, key + ": expected an integer");
  return *i;
}

std::string read_text(const TomlSource& src, const toml::node& n, const std::string& key) {
  const auto s = n.value_exact<std::string>();
  if (!s) src.fail(&n, fmt::format("{}: expected a string", key));
  return *s;
}

// A name of `names`: its index, or a failure naming them (and the closest).
std::int64_t read_choice(const TomlSource& src, const toml::node& n, const std::string& key,
                         const std::vector<std::string_view>& names) {
  const std::string s = read_text(src, n, key);
  const auto it = std::find(names.begin(), names.end(), s);
  if (it != names.end()) return it - names.begin();
  const auto best = io::suggest_value(s, names);
  src.fail(&n, fmt::format("{}: \"{}\" is not one of {}{}", key, s, quoted_list(names),
                           best ? fmt::format(" (did you mean \"{}\"?)", *best) : std::string()));
}

std::string toml_value_text(const toml::node& v) {
  std::ostringstream ss;
  v.visit([&](const auto& x) { ss << toml::toml_formatter{x}; });
  return ss.str();
}

std::vector<io::SceneSetting> read_settings(const TomlSource& src, const toml::node& n, const std::string& key) {
  const toml::table* t = n.as_table();
  if (!t) src.fail(&n, key + ": expected a table of \"table.key\" = value");
  std::vector<io::SceneSetting> out;
  for (const auto& [k, v] : *t) {
    const std::string where = v.source().begin.line > 0 ? fmt::format("{}:{}", src.file, v.source().begin.line)
                                                        : src.file;
    out.push_back({std::string(k.str()) + "=" + toml_value_text(v), where});
  }
  return out;
}

std::vector<std::string_view> method_names(const TomlSource& src) {
  std::vector<std::string_view> names;
  for (const MethodSyntax* r : src.methods->list())
    if (r->selection != MethodSelection::wraps) names.push_back(r->name);
  return names;
}

const toml::array& read_array(const TomlSource& src, const toml::node& n, const std::string& key, const char* what) {
  const toml::array* a = n.as_array();
  if (!a) src.fail(&n, fmt::format("{}: expected an array of {}", key, what));
  return *a;
}

}  // namespace

OptionValue read_option_value(const TomlSource& src, const toml::node& node, const std::string& key,
                              const OptionSpec& spec) {
  OptionValue v;
  auto in_range = [&](const toml::node& n, double x) {
    if (std::string e = check_option_range(spec, key, x); !e.empty()) src.fail(&n, e);
  };
  switch (spec.kind) {
    case OptionKind::real: v.real = read_real(src, node, key); in_range(node, v.real); break;
    case OptionKind::integer:
      v.integer = read_integer(src, node, key);
      in_range(node, static_cast<double>(v.integer));
      break;
    case OptionKind::text: v.text = read_text(src, node, key); break;
    case OptionKind::choice: v.integer = read_choice(src, node, key, spec.choices); break;
    case OptionKind::method: {
      const std::vector<std::string_view> names = method_names(src);
      v.text = std::string(names[static_cast<std::size_t>(read_choice(src, node, key, names))]);
      break;
    }
    case OptionKind::reals:
      for (const auto& e : read_array(src, node, key, "numbers")) {
        v.reals.push_back(read_real(src, e, key));
        in_range(e, v.reals.back());
      }
      break;
    case OptionKind::integers:
      for (const auto& e : read_array(src, node, key, "integers")) {
        v.integers.push_back(read_integer(src, e, key));
        in_range(e, static_cast<double>(v.integers.back()));
      }
      break;
    case OptionKind::settings: v.settings = read_settings(src, node, key); break;
  }
  return v;
}

std::string unknown_option_text(const std::string& key, const std::vector<const OptionSpec*>& specs,
                                const std::string& known_prefix, const std::vector<std::string>& others) {
  std::vector<std::string> known;
  std::vector<std::string_view> last;  // the names as typed in the key's table
  for (const OptionSpec* s : specs) {
    known.push_back(known_prefix + std::string(s->key));
    last.push_back(s->key);
  }
  const std::size_t dot = key.rfind('.');
  const std::string typed = dot == std::string::npos ? key : key.substr(dot + 1);
  const auto best = io::suggest_value(typed, last);
  std::string list;
  for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
  for (const std::string& k : others) list += (list.empty() ? "" : ", ") + k;
  const std::string prefix = dot == std::string::npos ? std::string() : key.substr(0, dot + 1);
  return fmt::format("unknown key '{}'{} (known: {})", key,
                     best ? fmt::format("; did you mean {}{}?", prefix, *best) : std::string(), list);
}

namespace detail {

std::string write_option_value(const OptionSpec& spec, double real, std::int64_t integer, const std::string& text,
                               const std::vector<double>& reals, const std::vector<std::int64_t>& integers) {
  std::string list;
  switch (spec.kind) {
    case OptionKind::real: return io::toml_double(real);
    case OptionKind::integer: return fmt::format("{}", integer);
    case OptionKind::choice: return io::toml_string(spec.choices.at(static_cast<std::size_t>(integer)));
    case OptionKind::text:
    case OptionKind::method: return io::toml_string(text);
    case OptionKind::reals:
      for (double x : reals) list += (list.empty() ? "" : ", ") + io::toml_double(x);
      return fmt::format("[{}]", list);
    case OptionKind::integers:
      for (std::int64_t x : integers) list += fmt::format("{}{}", list.empty() ? "" : ", ", x);
      return fmt::format("[{}]", list);
    case OptionKind::settings: return {};
  }
  return {};
}

std::string missing_option_text(const std::string& prefix, const OptionSpec& spec) {
  const std::string where = prefix.empty() ? std::string() : prefix.substr(0, prefix.size() - 1) + ": ";
  const std::string what =
      spec.kind == OptionKind::choice ? "one of " + quoted_list(spec.choices) : std::string(spec.doc);
  return fmt::format("{}missing '{}' ({})", where, spec.key, what);
}

}  // namespace detail
}  // namespace truss::campaign
