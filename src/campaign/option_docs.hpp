// The reference of a campaign file's keys in docs/campaigns.md: one table per TOML table, made from
// the option tables (campaign_tables.hpp, failure.hpp, and each row of the method catalog), so the
// page says what the parser reads. A test holds the page to it.
#pragma once
#include <string>

#include "campaign/method_options.hpp"

namespace truss::campaign {

// Markdown: for each table its name, what it is, and per key its value, unit, range, default and
// meaning; the methods' tables in the catalog's order.
std::string make_option_reference(const MethodCatalog& methods);

// The lines that bound the reference in docs/campaigns.md.
inline constexpr const char* kOptionReferenceBegin = "<!-- option reference: made from the option tables -->";
inline constexpr const char* kOptionReferenceEnd = "<!-- end of the option reference -->";

}  // namespace truss::campaign
