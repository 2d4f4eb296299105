// Reading a campaign file inside campaign/ (campaign.cpp): the method catalog's part of it
// (campaign_method.cpp). Methods read their tables through method_input.hpp.
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include <toml++/toml.h>

#include "campaign/campaign.hpp"
#include "campaign/option_table.hpp"

namespace truss::campaign::detail {

// [ensemble.<row>]: a table, or false (none).
void check_method_key(const TomlSource& c, const std::string& key, const toml::node& v);
// A root table that a row of the catalog reads ([failure]) or is chosen by ([sweep]).
bool is_method_table(const TomlSource& c, std::string_view root_table);
// Those root tables, each once, in table order.
std::vector<std::string> method_root_tables(const TomlSource& c);
// The chosen row (a composite chosen by its table, around the method ensemble.method names) reads
// its tables into o.ensemble.method; a run count it chooses is n_runs.
void parse_method(const TomlSource& c, const toml::table& root, CampaignOptions& o);

}  // namespace truss::campaign::detail
