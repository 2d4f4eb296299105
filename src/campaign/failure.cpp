// [failure] of a campaign file (failure.hpp): parsed, checked, written back.
#include "campaign/failure.hpp"

#include <cmath>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/toml_read.hpp"

namespace truss::campaign {

std::string validate_failure_column(const FailureOptions& f) {
  const std::string field = f.kind == FailureKind::margin ? "failure.margin" : "failure.column";
  const std::string unit = find_run_column_unit(f.column);
  if (unit.empty())
    return fmt::format("{}: \"{}\" is not a float64 column of /runs (a RunResult output, e.g. rail_margin_m, "
                       "peak_drive_force_N)", field, f.column);
  if (f.kind != FailureKind::margin && f.unit != unit)
    return fmt::format("failure.unit: \"{}\", but {} is in \"{}\" (give the threshold in the column's unit)", f.unit,
                       f.column, unit);
  return {};
}

std::string failure_toml(const FailureOptions& f) {
  if (f.kind == FailureKind::none) return {};
  if (f.kind == FailureKind::margin) return fmt::format("[failure]\nmargin = \"{}\"\n\n", f.column);
  return fmt::format("[failure]\ncolumn = \"{}\"\n{} = {}\nunit = \"{}\"\n\n", f.column,
                     f.kind == FailureKind::above ? "above" : "below", f.threshold, f.unit);
}

namespace detail {

void parse_failure_table(const Ctx& c, const toml::table& t, FailureOptions& f) {
  f.line = static_cast<int>(t.source().begin.line);
  const toml::node *margin = t.get("margin"), *column = t.get("column"), *above = t.get("above"),
                   *below = t.get("below"), *unit = t.get("unit");
  for (const auto& [k, v] : t)
    if (k != "margin" && k != "column" && k != "above" && k != "below" && k != "unit")
      c.fail(&v, unknown_key_text("failure." + std::string(k.str()),
                                  "failure.margin, failure.column, failure.above, failure.below, failure.unit"));
  if ((margin != nullptr) == (column != nullptr))
    c.fail(margin ? margin : column ? column : &t,
           "failure: give either margin = \"<column>\" (failed when <= 0, e.g. \"rail_margin_m\") or column = "
           "\"<column>\" with above = or below = a threshold and unit = the column's unit");
  if (margin) {
    if (above || below || unit)
      c.fail(above ? above : below ? below : unit,
             "failure: a margin fails at 0; above, below and unit go with column");
    f.kind = FailureKind::margin;
    f.column = get_string(c, *margin, "failure.margin");
    return;
  }
  f.column = get_string(c, *column, "failure.column");
  if ((above != nullptr) == (below != nullptr))
    c.fail(above ? above : column, "failure: a column fails above or below a threshold: give one of above, below");
  f.kind = above ? FailureKind::above : FailureKind::below;
  f.threshold = get_number(c, above ? *above : *below, above ? "failure.above" : "failure.below");
  if (!std::isfinite(f.threshold)) c.fail(above ? above : below, "failure: the threshold must be finite");
  if (!unit) c.fail(column, fmt::format("failure.unit: missing: say the threshold's unit (the column {} is in {})",
                                        f.column, find_run_column_unit(f.column)));
  f.unit = get_string(c, *unit, "failure.unit");
}

void parse_sweep_failure(const Ctx& c, const toml::table& root, FailureOptions& f) {
  const toml::node* t = root.get("failure");
  if (t == nullptr) return;
  if (root.get("sweep") == nullptr)
    c.fail(t, "failure: only ensemble.method = \"subset\" reads [failure] (or a [sweep], at each of its values)");
  if (!t->as_table()) c.fail(t, "'failure' must be a table");
  parse_failure_table(c, *t->as_table(), f);
}

}  // namespace detail
}  // namespace truss::campaign
