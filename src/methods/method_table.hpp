// The method table: one row per method, name -> how its options are read (campaign/method_options.hpp)
// and how the method is made. ensemble.method names a row; the campaign parser reads the row's
// tables through it, and every rank makes the campaign's method from it. Adding a method is its
// file (its Method, its options with their validate() and the row's parse) and one row here.
//
// A composite method reads its inner methods' tables through the catalog its parser is given
// (MethodInput::ctx.methods) and makes them with MethodTable::make from its own make.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "campaign/method_options.hpp"
#include "methods/method.hpp"

namespace truss::methods {

class MethodTable;

struct MethodRow {
  campaign::MethodSyntax syntax;  // name, tables, options parser
  // The method of a campaign whose ensemble.method is this row (its options are the row's).
  std::function<std::unique_ptr<Method>(const campaign::CampaignContext&, const MethodTable&)> make;
};

class MethodTable final : public campaign::MethodCatalog {
 public:
  explicit MethodTable(std::vector<MethodRow> rows);
  const campaign::MethodSyntax* find(std::string_view name) const override;
  std::vector<const campaign::MethodSyntax*> list() const override;
  // The method of ctx.options.ensemble.method (with a [sweep], the composite that makes the method
  // ensemble.method names at each of its values from this table).
  std::unique_ptr<Method> make(const campaign::CampaignContext& ctx) const;
  // This table and one row more (a test's method).
  MethodTable with(MethodRow row) const;

 private:
  std::vector<MethodRow> rows_;
};

// A row's make for a method whose constructor takes the campaign alone.
template <class M>
std::unique_ptr<Method> make_method_of(const campaign::CampaignContext& ctx, const MethodTable&) {
  return std::make_unique<M>(ctx);
}

// design (Monte Carlo, Latin hypercube, Sobol', Saltelli), stop, subset; sweep, the composite.
const MethodTable& builtin_methods();

// builtin_methods().make(ctx).
std::unique_ptr<Method> make_method(const campaign::CampaignContext& ctx);

// The campaign parser (campaign/campaign.hpp) with the built-in methods.
campaign::CampaignOptions parse_campaign_file(const std::string& path, const std::vector<std::string>& overrides = {});
campaign::CampaignOptions parse_campaign_text(std::string_view text, const std::string& source_name,
                                              const std::string& base_dir,
                                              const std::vector<std::string>& overrides = {});

}  // namespace truss::methods
