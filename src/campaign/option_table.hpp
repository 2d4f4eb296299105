// Option tables: one row per key of a campaign TOML table (the campaign's own tables and each
// method's), as the scene's key table (sim/scene_keys.hpp) is for scene keys: the key, the member
// it sets, its kind, unit, range and one line saying what it is. From the rows come the reader
// (typed values, ranges, an unknown key refused with the table's keys and a "did you mean", every
// message naming the file and line or the --set), the resolved TOML, and the reference tables of
// docs/campaigns.md (campaign/option_docs.hpp). A method's options are a struct and its rows.
//
//   const OptionTable<MyOptions>& table() {
//     static const OptionTable<MyOptions> t{"ensemble.mine", "what the method does", {
//         TRUSS_OPTION_REAL(MyOptions, "width", width, "1", kPositive, "the interval's half-width"),
//     }};
//     return t;
//   }
//   read_options(in.source, *in.table, table(), options, in.prefix);   // in the row's parse
//   "[ensemble.mine]\n" + write_options(table(), options) + "\n";     // in to_toml()
#pragma once
#include <cmath>
#include <cstdint>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <toml++/toml.h>

#include "io/scene_toml.hpp"

namespace truss::campaign {

class MethodCatalog;

// Where a campaign's values came from: the file (each node's line), the --set that put a value in
// the tree, and the method catalog that ensemble.method names a row of. Every reader fails with it.
struct TomlSource {
  std::string file;
  std::map<const toml::node*, std::string> set_by;  // values put in the tree by --set: the argument
  const MethodCatalog* methods = nullptr;
  // Throws io::InputError "error: FILE:LINE: what" (or "error: --set ARG: what").
  [[noreturn]] void fail(const toml::node* at, const std::string& what) const;
};

// What a key holds. choice: one of its row's names (the member an enum, in the names' order);
// settings: a table of "table.key" = value (scene settings, each with its file:line); method: the
// name of a row of the method catalog.
enum class OptionKind { real, integer, text, choice, reals, integers, settings, method };

// A closed, open or half-bounded interval of a number's values.
struct OptionRange {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool lo_open = false, hi_open = false;
  bool contains(double v) const { return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi); }
  bool is_bounded() const { return std::isfinite(lo) || std::isfinite(hi); }
  std::string text() const;  // "[1, 1000]", "(0, 1)", ">= 0", "> 0"
};
inline constexpr OptionRange kAnyNumber{};
constexpr OptionRange closed_range(double lo, double hi) { return {lo, hi, false, false}; }
constexpr OptionRange open_range(double lo, double hi) { return {lo, hi, true, true}; }
constexpr OptionRange at_least(double lo) { return {lo, std::numeric_limits<double>::infinity(), false, false}; }
constexpr OptionRange above(double lo) { return {lo, std::numeric_limits<double>::infinity(), true, false}; }

// A row without its accessors: what the reader, the messages and the docs need.
struct OptionSpec {
  std::string_view key{};
  OptionKind kind = OptionKind::real;
  std::string_view unit{};                  // numbers: SI, "1" for counts and ratios
  OptionRange range{};                      // numbers: a value outside it is refused where it is read
  std::string_view doc{};                   // what it is, one line
  std::vector<std::string_view> choices{};  // choice: the names, in the enum's order
  bool required = false;                    // a table without it is refused
};

// A value as read from the file, checked against its row (the part of its kind).
struct OptionValue {
  double real = 0.0;
  std::int64_t integer = 0;  // integer; choice: the index of the name
  std::string text;          // text, method
  std::vector<double> reals;
  std::vector<std::int64_t> integers;
  std::vector<io::SceneSetting> settings;
};

template <class T>
struct OptionRow {
  OptionSpec spec;
  // The accessors of its kind (choice: the index, as integer).
  void (*set_real)(T&, double) = nullptr;
  double (*get_real)(const T&) = nullptr;
  void (*set_int)(T&, std::int64_t) = nullptr;
  std::int64_t (*get_int)(const T&) = nullptr;
  void (*set_text)(T&, const std::string&) = nullptr;
  std::string (*get_text)(const T&) = nullptr;
  void (*set_reals)(T&, const std::vector<double>&) = nullptr;
  std::vector<double> (*get_reals)(const T&) = nullptr;
  void (*set_ints)(T&, const std::vector<std::int64_t>&) = nullptr;
  std::vector<std::int64_t> (*get_ints)(const T&) = nullptr;
  void (*set_settings)(T&, const std::vector<io::SceneSetting>&) = nullptr;
  // Whether the resolved TOML writes it: null always; else when it returns true (never_written:
  // a key that only shapes others, as sweep.from, or that the resolved form replaces).
  bool (*written)(const T&) = nullptr;
};

// The names of an enum's values, from its table of names (sampling::kSamplingNames).
template <std::size_t N>
std::vector<std::string_view> choice_names(const char* const (&names)[N]) {
  return std::vector<std::string_view>(std::begin(names), std::end(names));
}

template <class T>
bool never_written(const T&) { return false; }
// A row as built, written only when `when` says so, or required.
template <class T>
OptionRow<T> written_if(OptionRow<T> row, bool (*when)(const T&)) {
  row.written = when;
  return row;
}
template <class T>
OptionRow<T> required(OptionRow<T> row) {
  row.spec.required = true;
  return row;
}

// Names the rows cannot hold but the table takes (subtables such as [ensemble.stop]): `take`
// returns true for such a key (after checking it), and `names` lists them for messages.
struct OtherKeys {
  std::function<bool(std::string_view key, const toml::node& value)> take;
  std::vector<std::string> names;  // as the known keys show them: "[ensemble.stop]"
};

template <class T>
struct OptionTable {
  std::string name;  // its path in the file ("ensemble.stop"); an array of tables: "[[dispersion]]"
  std::string doc;   // what the table is, one sentence (the docs' reference)
  std::vector<OptionRow<T>> rows;
  const OptionRow<T>* find(std::string_view key) const {
    for (const OptionRow<T>& r : rows)
      if (r.spec.key == key) return &r;
    return nullptr;
  }
  std::vector<const OptionSpec*> specs() const {
    std::vector<const OptionSpec*> s;
    for (const OptionRow<T>& r : rows) s.push_back(&r.spec);
    return s;
  }
  // The prefix of its keys in the list of known keys ("ensemble.stop."; none for an array's).
  std::string known_prefix() const { return name.rfind("[[", 0) == 0 ? std::string() : name + "."; }
};

// A table as the reference in docs/campaigns.md shows it: its rows, and each one's default as the
// resolved TOML writes it (from the options' defaults; "" for a required key or none).
struct TableDoc {
  std::string name, doc;
  std::vector<OptionSpec> rows;
  std::vector<std::string> defaults;
  std::vector<std::string> others;  // what the table holds besides its keys ("[ensemble.stop]")
};

// The value of `node` for the row `spec`, named `key` in messages ("ensemble.stop.width: expected a
// number"); fails with src on a wrong type, a number outside the range, an unknown choice.
OptionValue read_option_value(const TomlSource& src, const toml::node& node, const std::string& key,
                              const OptionSpec& spec);
// "unknown key 'KEY'; did you mean NAME? (known: ...)": the rows' keys with `known_prefix`, then `others`.
std::string unknown_option_text(const std::string& key, const std::vector<const OptionSpec*>& specs,
                                const std::string& known_prefix, const std::vector<std::string>& others);
// "key: must lie in RANGE UNIT, got V" when v is outside the row's range, else "".
std::string check_option_range(const OptionSpec& spec, const std::string& key, double v);

namespace detail {

template <class T>
void set_option(const OptionRow<T>& row, OptionValue&& v, T& o) {
  switch (row.spec.kind) {
    case OptionKind::real: return row.set_real(o, v.real);
    case OptionKind::integer:
    case OptionKind::choice: return row.set_int(o, v.integer);
    case OptionKind::text:
    case OptionKind::method: return row.set_text(o, v.text);
    case OptionKind::reals: return row.set_reals(o, v.reals);
    case OptionKind::integers: return row.set_ints(o, v.integers);
    case OptionKind::settings: return row.set_settings(o, v.settings);
  }
}

std::string write_option_value(const OptionSpec& spec, double real, std::int64_t integer, const std::string& text,
                               const std::vector<double>& reals, const std::vector<std::int64_t>& integers);
// "PREFIX: missing 'KEY' (what it is)".
std::string missing_option_text(const std::string& prefix, const OptionSpec& spec);

}  // namespace detail

// Reads the keys of `t` into `o` through the table's rows; `prefix` names them in messages
// ("ensemble.stop.", "dispersion[2]."). A key of no row is passed to `others.take`, else refused.
template <class T>
void read_options(const TomlSource& src, const toml::table& t, const OptionTable<T>& table, T& o,
                  const std::string& prefix, const OtherKeys& others = {}) {
  for (const auto& [k, v] : t) {
    const std::string key = prefix + std::string(k.str());
    const OptionRow<T>* row = table.find(k.str());
    if (row == nullptr) {
      if (others.take && others.take(k.str(), v)) continue;
      src.fail(&v, unknown_option_text(key, table.specs(), table.known_prefix(), others.names));
    }
    detail::set_option(*row, read_option_value(src, v, key, row->spec), o);
  }
  for (const OptionRow<T>& row : table.rows)
    if (row.spec.required && !t.contains(row.spec.key)) src.fail(&t, detail::missing_option_text(prefix, row.spec));
}

// The rows' ranges over options built in code: "" or "PREFIX.key: must lie in ..., got v". Rows
// the options do not write (sweep.from, the keys of another distribution) hold nothing to check.
template <class T>
std::string check_option_ranges(const OptionTable<T>& table, const T& o, const std::string& prefix) {
  for (const OptionRow<T>& row : table.rows) {
    if (row.written != nullptr && !row.written(o)) continue;
    const std::string key = prefix + std::string(row.spec.key);
    std::string e;
    if (row.spec.kind == OptionKind::real) e = check_option_range(row.spec, key, row.get_real(o));
    if (row.spec.kind == OptionKind::integer)
      e = check_option_range(row.spec, key, static_cast<double>(row.get_int(o)));
    if (!e.empty()) return e;
  }
  return {};
}

namespace detail {
template <class T>
std::string write_row(const OptionRow<T>& r, const T& o) {
  const OptionKind k = r.spec.kind;
  const bool number = k == OptionKind::integer || k == OptionKind::choice;
  const bool text = k == OptionKind::text || k == OptionKind::method;
  return write_option_value(r.spec, k == OptionKind::real ? r.get_real(o) : 0.0, number ? r.get_int(o) : 0,
                            text ? r.get_text(o) : std::string(),
                            k == OptionKind::reals ? r.get_reals(o) : std::vector<double>{},
                            k == OptionKind::integers ? r.get_ints(o) : std::vector<std::int64_t>{});
}
}  // namespace detail

// The table for the reference: its defaults are those of T{}.
template <class T>
TableDoc describe_options(const OptionTable<T>& table, std::vector<std::string> others = {}) {
  TableDoc d{table.name, table.doc, {}, {}, std::move(others)};
  const T defaults{};
  for (const OptionRow<T>& r : table.rows) {
    d.rows.push_back(r.spec);
    // No default to show: a required key, a table, the method's name, or a key the defaults do not write.
    const bool none = r.spec.required || r.spec.kind == OptionKind::settings || r.spec.kind == OptionKind::method ||
                      (r.written != nullptr && !r.written(defaults));
    d.defaults.push_back(none ? std::string() : detail::write_row(r, defaults));
  }
  return d;
}

// "key = value\n" for each row the resolved TOML writes, in the rows' order.
template <class T>
std::string write_options(const OptionTable<T>& table, const T& o) {
  std::string out;
  for (const OptionRow<T>& r : table.rows)
    if (r.spec.kind != OptionKind::settings && (r.written == nullptr || r.written(o)))
      out += std::string(r.spec.key) + " = " + detail::write_row(r, o) + "\n";
  return out;
}

}  // namespace truss::campaign

// Row builders. T: the options struct; KEY: the key as written; M: the member (a path, e.g.
// rule.level); UNIT, RANGE, DOC: as OptionSpec. Integers and choices convert to the member's type
// (the range keeps an integer within it; a choice's names are the enum's values in order).
#define TRUSS_OPTION_REAL(T, KEY, M, UNIT, RANGE, DOC)                                          \
  ::truss::campaign::OptionRow<T> {                                                             \
    {KEY, ::truss::campaign::OptionKind::real, UNIT, RANGE, DOC}, [](T& o, double v) { o.M = v; }, \
        [](const T& o) -> double { return o.M; }                                                \
  }
#define TRUSS_OPTION_INT(T, KEY, M, UNIT, RANGE, DOC)                                              \
  ::truss::campaign::OptionRow<T> {                                                                \
    {KEY, ::truss::campaign::OptionKind::integer, UNIT, RANGE, DOC}, nullptr, nullptr,             \
        [](T& o, std::int64_t v) { o.M = static_cast<std::remove_reference_t<decltype(o.M)>>(v); }, \
        [](const T& o) -> std::int64_t { return static_cast<std::int64_t>(o.M); }                  \
  }
#define TRUSS_OPTION_TEXT(T, KEY, M, DOC)                                                                     \
  ::truss::campaign::OptionRow<T> {                                                                           \
    {KEY, ::truss::campaign::OptionKind::text, "", {}, DOC}, nullptr, nullptr, nullptr, nullptr,              \
        [](T& o, const std::string& v) { o.M = v; }, [](const T& o) -> std::string { return o.M; }            \
  }
#define TRUSS_OPTION_CHOICE(T, KEY, M, DOC, ...)                                                        \
  ::truss::campaign::OptionRow<T> {                                                                     \
    {KEY, ::truss::campaign::OptionKind::choice, "", {}, DOC, {__VA_ARGS__}}, nullptr, nullptr,         \
        [](T& o, std::int64_t v) { o.M = static_cast<std::remove_reference_t<decltype(o.M)>>(v); },     \
        [](const T& o) -> std::int64_t { return static_cast<std::int64_t>(o.M); }                       \
  }
#define TRUSS_OPTION_REALS(T, KEY, M, UNIT, DOC)                                                          \
  ::truss::campaign::OptionRow<T> {                                                                       \
    {KEY, ::truss::campaign::OptionKind::reals, UNIT, {}, DOC}, nullptr, nullptr, nullptr, nullptr, nullptr, \
        nullptr, [](T& o, const std::vector<double>& v) { o.M = v; },                                     \
        [](const T& o) -> std::vector<double> { return o.M; }                                             \
  }
#define TRUSS_OPTION_INTS(T, KEY, M, UNIT, RANGE, DOC)                                                     \
  ::truss::campaign::OptionRow<T> {                                                                         \
    {KEY, ::truss::campaign::OptionKind::integers, UNIT, RANGE, DOC}, nullptr, nullptr, nullptr, nullptr,    \
        nullptr, nullptr, nullptr, nullptr, [](T& o, const std::vector<std::int64_t>& v) { o.M = v; },       \
        [](const T& o) -> std::vector<std::int64_t> { return o.M; }                                         \
  }
