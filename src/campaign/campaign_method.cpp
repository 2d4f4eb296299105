// How a campaign chooses its runs (method_options.hpp): ensemble.method and the chosen row's own
// tables read through the method catalog; tables of other rows refused; a run count the method
// chooses itself set as ensemble.n_runs; the method's part of the resolved TOML.
#include <algorithm>

#include <fmt/format.h>

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

namespace detail {

namespace {

// [ensemble.<name>] of a row, or null (absent, or `= false`).
const toml::table* own_table(const toml::table& root, const MethodSyntax& row) {
  const toml::table* e = root["ensemble"].as_table();
  return e ? (*e)[row.name].as_table() : nullptr;
}

// The row of ensemble.method; under "design", a row selected by its table when that table is there.
const MethodSyntax& choose_row(const Ctx& c, const toml::table& root) {
  const toml::node* m = root.at_path("ensemble.method").node();
  // A name of the catalog: parse_ensemble_table has checked it.
  const std::string name = m ? *m->value<std::string>() : kDefaultMethod;
  const MethodSyntax* row = c.methods->find(name);
  if (name != kDefaultMethod) return *row;
  for (const MethodSyntax* r : c.methods->list())
    if (r->selected_by_table && own_table(root, *r) != nullptr) {
      if (row->name != kDefaultMethod)
        c.fail(own_table(root, *r), fmt::format("ensemble.{}: [ensemble.{}] and [ensemble.{}] each choose a method; "
                                                "give one", r->name, row->name, r->name));
      row = r;
    }
  return *row;
}

}  // namespace

bool is_method_table(const Ctx& c, std::string_view root_table) {
  for (const MethodSyntax* r : c.methods->list())
    if (std::find(r->root_tables.begin(), r->root_tables.end(), root_table) != r->root_tables.end()) return true;
  return false;
}

std::vector<std::string> method_root_tables(const Ctx& c) {
  std::vector<std::string> tables;
  for (const MethodSyntax* r : c.methods->list())
    for (const std::string& t : r->root_tables)
      if (std::find(tables.begin(), tables.end(), t) == tables.end()) tables.push_back(t);
  return tables;
}

void check_method_key(const Ctx& c, const std::string& key, const toml::node& v) {
  if (v.as_table() == nullptr && v.value_exact<bool>() != std::optional<bool>(false))
    c.fail(&v, fmt::format("{} must be a table ([{}]), or false for none", key, key));
}

std::vector<std::string> method_names(const Ctx& c) {
  std::vector<std::string> names;
  for (const MethodSyntax* r : c.methods->list()) names.push_back(r->name);
  return names;
}

void parse_method(const Ctx& c, const toml::table& root, CampaignOptions& o) {
  const MethodSyntax& row = choose_row(c, root);
  for (const MethodSyntax* r : c.methods->list()) {  // the tables of other rows: nothing reads them
    if (r == &row) continue;
    if (const toml::table* t = own_table(root, *r); t != nullptr)
      c.fail(t, fmt::format("ensemble.{}: [ensemble.{}] goes with ensemble.method = \"{}\", not \"{}\"; remove it",
                            r->name, r->name, r->name, row.name));
    for (const std::string& name : r->root_tables)
      if (const toml::node* t = root.get(name);
          t != nullptr && std::find(row.root_tables.begin(), row.root_tables.end(), name) == row.root_tables.end())
        c.fail(t, fmt::format("{}: only ensemble.method = \"{}\" reads [{}]", name, r->name, name));
  }
  std::unique_ptr<MethodOptions> options = row.parse({c, root, own_table(root, row), "ensemble." + row.name + "."});
  const std::string chosen = options->chosen_runs();
  o.ensemble.method = MethodChoice(row.name, row.selected_by_table ? kDefaultMethod : row.name, std::move(options));
  if (chosen.empty()) return;
  if (const toml::node* n = root.at_path("ensemble.n_runs").node())
    c.fail(n, fmt::format("ensemble.n_runs: method = \"{}\" chooses its runs ({}); remove n_runs", row.name, chosen));
  if (const std::int64_t n = o.ensemble.method.options().calc_n_runs(o); n > 0) o.ensemble.n_runs = n;
}

}  // namespace detail
}  // namespace truss::campaign
