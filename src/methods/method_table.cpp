#include "methods/method_table.hpp"

#include <stdexcept>

#include "methods/fixed_design.hpp"
#include "methods/importance_method.hpp"
#include "methods/importance_sweep.hpp"
#include "methods/stop_method.hpp"
#include "methods/subset_method.hpp"
#include "methods/sweep_method.hpp"

namespace truss::methods {

MethodTable::MethodTable(std::vector<MethodRow> rows) : rows_(std::move(rows)) {
  for (std::size_t i = 0; i < rows_.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (rows_[i].syntax.name == rows_[j].syntax.name)
        throw std::logic_error("method table: two rows named " + rows_[i].syntax.name);
}

const campaign::MethodSyntax* MethodTable::find(std::string_view name) const {
  for (const MethodRow& r : rows_)
    if (r.syntax.name == name) return &r.syntax;
  return nullptr;
}

std::vector<const campaign::MethodSyntax*> MethodTable::list() const {
  std::vector<const campaign::MethodSyntax*> v;
  for (const MethodRow& r : rows_) v.push_back(&r.syntax);
  return v;
}

std::unique_ptr<Method> MethodTable::make(const campaign::CampaignContext& ctx) const {
  for (const MethodRow& r : rows_)
    if (r.syntax.name == ctx.options.ensemble.method.name()) return r.make(ctx, *this);
  throw std::logic_error("ensemble.method \"" + ctx.options.ensemble.method.name() + "\" is not in the method table");
}

MethodTable MethodTable::with(MethodRow row) const {
  std::vector<MethodRow> rows = rows_;
  rows.push_back(std::move(row));
  return MethodTable(std::move(rows));
}

namespace {
constexpr auto by_name = campaign::MethodSelection::by_name, by_own_table = campaign::MethodSelection::by_own_table,
               wraps = campaign::MethodSelection::wraps;
std::unique_ptr<Method> make_sweep_method(const campaign::CampaignContext& ctx, const MethodTable& table) {
  // Importance sampling's runs serve every value by reweighting (importance_sweep.hpp).
  if (ctx.options.ensemble.method.as<SweepOptions>().inner.name() == "importance")
    return std::make_unique<ImportanceSweepMethod>(ctx);
  return std::make_unique<SweepMethod>(ctx, table);
}
}  // namespace

const MethodTable& builtin_methods() {
  static const MethodTable table({
      {{campaign::kDefaultMethod, {"failure"}, by_name, &DesignOptions::parse}, &make_fixed_design},
      {{"stop", {"failure"}, by_own_table, &StopOptions::parse, &StopOptions::table_doc}, &make_method_of<StopMethod>},
      {{"subset", {"failure"}, by_name, &SubsetMethodOptions::parse, &SubsetMethodOptions::table_doc},
       &make_method_of<SubsetMethod>},
      {{"importance", {"failure"}, by_name, &ImportanceMethodOptions::parse, &ImportanceMethodOptions::table_doc},
       &make_method_of<ImportanceMethod>},
      // A composite: chosen by [sweep], it runs the method ensemble.method names at each value.
      {{"sweep", {}, wraps, &SweepOptions::parse, &SweepOptions::table_doc}, &make_sweep_method},
  });
  return table;
}

std::unique_ptr<Method> make_method(const campaign::CampaignContext& ctx) { return builtin_methods().make(ctx); }

campaign::CampaignOptions parse_campaign_file(const std::string& path, const std::vector<std::string>& overrides) {
  return campaign::parse_campaign_file(path, builtin_methods(), overrides);
}

campaign::CampaignOptions parse_campaign_text(std::string_view text, const std::string& source_name,
                                              const std::string& base_dir, const std::vector<std::string>& overrides) {
  return campaign::parse_campaign_text(text, source_name, base_dir, builtin_methods(), overrides);
}

}  // namespace truss::methods
