// How a campaign chooses its runs (method_options.hpp): ensemble.method and the chosen row's own
// tables read through the method catalog (a composite's around the method it runs); tables of
// other rows refused; a run count the method chooses itself set as ensemble.n_runs.
#include <algorithm>

#include <fmt/format.h>

#include "campaign/method_input.hpp"
#include "campaign/toml_read.hpp"
#include "io/json_summary.hpp"

namespace truss::campaign {

std::int64_t MethodOptions::calc_max_runs(const CampaignOptions& c) const { return c.ensemble.n_runs; }
std::string MethodOptions::describe_max_runs(const CampaignOptions& c) const {
  return fmt::format("ensemble.n_runs = {}", c.ensemble.n_runs);
}

std::string find_run_column_unit(const std::string& name) {
  if (name == "wall_time_s") return {};  // the record's run_wall_time_s: not an output
  const sim::RunResult none;
  for (const io::RunField& f : io::run_result_fields())
    if (name == f.name && std::holds_alternative<double>(f.get(none))) return f.units;
  return {};
}

namespace {

// A row's own table ([ensemble.<name>], a composite's [<name>]), or null (absent, or `= false`).
const toml::table* own_table(const toml::table& root, const MethodSyntax& row) {
  return root.at_path(row.own_table()).as_table();
}

// The row of ensemble.method; under "design", a row selected by its table when that table is there.
const MethodSyntax& choose_row(const TomlSource& c, const toml::table& root) {
  const toml::node* m = root.at_path("ensemble.method").node();
  // A name of the catalog: the [ensemble] reader has checked it.
  const std::string name = m ? *m->value<std::string>() : kDefaultMethod;
  const MethodSyntax* row = c.methods->find(name);
  if (name != kDefaultMethod) return *row;
  for (const MethodSyntax* r : c.methods->list())
    if (r->selection == MethodSelection::by_own_table && own_table(root, *r) != nullptr) {
      if (row->name != kDefaultMethod)
        c.fail(own_table(root, *r), fmt::format("ensemble.{}: [ensemble.{}] and [ensemble.{}] each choose a method; "
                                                "give one", r->name, row->name, r->name));
      row = r;
    }
  return *row;
}

// The composite whose table the file has ([sweep]), or null.
const MethodSyntax* find_composite(const TomlSource& c, const toml::table& root) {
  for (const MethodSyntax* r : c.methods->list())
    if (r->selection == MethodSelection::wraps && root.get(r->name) != nullptr) {
      if (!root.get(r->name)->as_table()) c.fail(root.get(r->name), fmt::format("'{}' must be a table", r->name));
      return r;
    }
  return nullptr;
}

// The rows that read a root table: "design, stop, subset".
std::string find_readers(const TomlSource& c, const std::string& table) {
  std::string names;
  for (const MethodSyntax* r : c.methods->list())
    if (std::find(r->root_tables.begin(), r->root_tables.end(), table) != r->root_tables.end())
      names += (names.empty() ? "" : ", ") + r->name;
  return names;
}

}  // namespace

MethodChoice read_method_choice(const MethodInput& in) {
  const TomlSource& c = in.source;
  const MethodSyntax& row = choose_row(c, in.root);
  for (const MethodSyntax* r : c.methods->list()) {  // the tables of other rows: nothing reads them
    if (r == &row || r->selection == MethodSelection::wraps) continue;
    if (const toml::table* t = own_table(in.root, *r); t != nullptr)
      c.fail(t, fmt::format("ensemble.{}: [ensemble.{}] goes with ensemble.method = \"{}\", not \"{}\"; remove it",
                            r->name, r->name, r->name, row.name));
    for (const std::string& name : r->root_tables)
      if (const toml::node* t = in.root.get(name);
          t != nullptr && std::find(row.root_tables.begin(), row.root_tables.end(), name) == row.root_tables.end())
        c.fail(t, fmt::format("{}: ensemble.method = \"{}\" reads no [{}] (the methods that do: {})", name, row.name,
                              name, find_readers(c, name)));
  }
  std::unique_ptr<MethodOptions> options = row.parse({c, in.root, own_table(in.root, row), row.own_table() + "."});
  const std::string written = row.selection == MethodSelection::by_own_table ? kDefaultMethod : row.name;
  return MethodChoice(row.name, written, std::move(options));
}

namespace detail {

bool is_method_table(const TomlSource& c, std::string_view root_table) {
  const std::vector<std::string> tables = method_root_tables(c);
  return std::find(tables.begin(), tables.end(), root_table) != tables.end();
}

std::vector<std::string> method_root_tables(const TomlSource& c) {
  std::vector<std::string> tables;
  for (const MethodSyntax* r : c.methods->list()) {
    std::vector<std::string> own = r->root_tables;
    if (r->selection == MethodSelection::wraps) own.push_back(r->name);
    for (const std::string& t : own)
      if (std::find(tables.begin(), tables.end(), t) == tables.end()) tables.push_back(t);
  }
  return tables;
}

void check_method_key(const TomlSource& c, const std::string& key, const toml::node& v) {
  if (v.as_table() == nullptr && v.value_exact<bool>() != std::optional<bool>(false))
    c.fail(&v, fmt::format("{} must be a table ([{}]), or false for none", key, key));
}

void parse_method(const TomlSource& c, const toml::table& root, CampaignOptions& o) {
  const MethodInput whole{c, root, nullptr, ""};
  if (const MethodSyntax* composite = find_composite(c, root)) {
    std::unique_ptr<MethodOptions> options =
        composite->parse({c, root, root.get(composite->name)->as_table(), composite->own_table() + "."});
    const std::string written = options->inner_method()->written_name();
    o.ensemble.method = MethodChoice(composite->name, written, std::move(options));
  } else {
    o.ensemble.method = read_method_choice(whole);
  }
  const MethodOptions& options = o.ensemble.method.options();
  const std::string chosen = options.chosen_runs();
  if (chosen.empty()) return;
  const std::string name = options.inner_method() ? options.inner_method()->name() : o.ensemble.method.name();
  if (const toml::node* n = root.at_path("ensemble.n_runs").node())
    c.fail(n, fmt::format("ensemble.n_runs: method = \"{}\" chooses its runs ({}); remove n_runs", name, chosen));
  if (const std::int64_t n = o.ensemble.method.options().calc_n_runs(o); n > 0) o.ensemble.n_runs = n;
}

}  // namespace detail
}  // namespace truss::campaign
