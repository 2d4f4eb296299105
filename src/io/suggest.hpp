// "Did you mean" suggestions for scene tables, keys and enumeration values: the closest known
// name by edit distance (prefixes count as close: "beta" ~ "beta_deg"), over the scene key table.
#pragma once
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace truss::io {

// Closest known "table.key" to a key typed in `table` (empty table: typed at the top level).
std::optional<std::string> suggest_key(std::string_view table, std::string_view key);
std::optional<std::string> suggest_table(std::string_view table);
std::optional<std::string> suggest_value(std::string_view value, const std::vector<std::string_view>& allowed);
// "[mast], [rail], ..." and "n_bays, strut_length_m, ..." for messages.
std::string known_tables_text();
std::string known_keys_text(std::string_view table);

}  // namespace truss::io
