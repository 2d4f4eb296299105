// [failure] of a campaign file (failure.hpp): its rows, read, checked, written back.
#include "campaign/failure.hpp"

#include <cmath>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/method_input.hpp"
#include "io/json_summary.hpp"

namespace truss::campaign {

namespace {

using F = FailureOptions;
bool is_margin(const F& f) { return f.kind == FailureKind::margin; }
bool is_threshold(const F& f) { return f.kind == FailureKind::above || f.kind == FailureKind::below; }
bool is_above(const F& f) { return f.kind == FailureKind::above; }
bool is_below(const F& f) { return f.kind == FailureKind::below; }

// The rules between the keys, once each is read: margin, or column with one threshold and its unit.
void check_failure_keys(const TomlSource& c, const toml::table& t, FailureOptions& f) {
  const toml::node *margin = t.get("margin"), *column = t.get("column"), *above = t.get("above"),
                   *below = t.get("below"), *unit = t.get("unit");
  if ((margin != nullptr) == (column != nullptr))
    c.fail(margin ? margin : column ? column : &t,
           "failure: give either margin = \"<column>\" (failed when <= 0, e.g. \"rail_margin_m\") or column = "
           "\"<column>\" with above = or below = a threshold and unit = the column's unit");
  if (margin) {
    if (above || below || unit)
      c.fail(above ? above : below ? below : unit,
             "failure: a margin fails at 0; above, below and unit go with column");
    return;
  }
  if ((above != nullptr) == (below != nullptr))
    c.fail(above ? above : column, "failure: a column fails above or below a threshold: give one of above, below");
  if (!std::isfinite(f.threshold)) c.fail(above ? above : below, "failure: the threshold must be finite");
  if (!unit) c.fail(column, fmt::format("failure.unit: missing: say the threshold's unit (the column {} is in {})",
                                        f.column, find_run_column_unit(f.column)));
}

}  // namespace

const OptionTable<FailureOptions>& failure_table() {
  static const OptionTable<F> t{
      "failure",
      "the failure event whose probability a method estimates: a margin column, or a column against a threshold",
      {
          written_if(OptionRow<F>{{"margin", OptionKind::text, "", {},
                                   "a float64 column of /runs that is a margin: the run fails when it is <= 0"},
                                  nullptr, nullptr, nullptr, nullptr,
                                  [](F& f, const std::string& v) {
                                    f.kind = FailureKind::margin;
                                    f.column = v;
                                  },
                                  [](const F& f) { return f.column; }},
                     &is_margin),
          written_if(TRUSS_OPTION_TEXT(F, "column", column, "a float64 column of /runs, with above or below"),
                     &is_threshold),
          written_if(OptionRow<F>{{"above", OptionKind::real, "the column's", {}, "fails when the column reaches it"},
                                  [](F& f, double v) {
                                    f.kind = FailureKind::above;
                                    f.threshold = v;
                                  },
                                  [](const F& f) { return f.threshold; }},
                     &is_above),
          written_if(OptionRow<F>{{"below", OptionKind::real, "the column's", {}, "fails when the column falls to it"},
                                  [](F& f, double v) {
                                    f.kind = FailureKind::below;
                                    f.threshold = v;
                                  },
                                  [](const F& f) { return f.threshold; }},
                     &is_below),
          written_if(TRUSS_OPTION_TEXT(F, "unit", unit, "the threshold's unit: the column's"), &is_threshold),
      }};
  return t;
}

void read_failure_event(const MethodInput& in, FailureOptions& f) {
  const toml::node* n = in.root.get("failure");
  if (n == nullptr) return;
  const toml::table* t = n->as_table();
  if (t == nullptr) in.source.fail(n, "'failure' must be a table");
  f.line = static_cast<int>(t->source().begin.line);
  read_options(in.source, *t, failure_table(), f, "failure.");
  check_failure_keys(in.source, *t, f);
}

std::string validate_failure_event(const FailureOptions& f, const CampaignOptions& c) {
  if (f.kind == FailureKind::none) return {};
  const std::string field = f.kind == FailureKind::margin ? "failure.margin" : "failure.column";
  const std::string unit = find_run_column_unit(f.column);
  if (unit.empty())
    return fmt::format("{}: \"{}\" is not a float64 column of /runs (a RunResult output, e.g. rail_margin_m, "
                       "peak_drive_force_N)", field, f.column);
  if (f.kind != FailureKind::margin && f.unit != unit)
    return fmt::format("failure.unit: \"{}\", but {} is in \"{}\" (give the threshold in the column's unit)", f.unit,
                       f.column, unit);
  for (const io::RunField& r : io::run_result_fields())
    if (r.name == f.column && r.defined_when != nullptr)
      if (const char* need = r.defined_when(c.base); need != nullptr)
        return fmt::format("{}: \"{}\" is defined only with {}: NaN in every run of this campaign's scene, so no run "
                           "would ever fail (margin or column one that the scene's modes compute)",
                           field, f.column, need);
  return {};
}

std::string failure_toml(const FailureOptions& f) {
  if (f.kind == FailureKind::none) return {};
  return "[failure]\n" + write_options(failure_table(), f) + "\n";
}

}  // namespace truss::campaign
