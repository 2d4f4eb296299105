// [sweep] (sweep_options.hpp): its rows, read, checked, written back.
#include "methods/sweep_options.hpp"

#include <cmath>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "methods/importance_sweep.hpp"

namespace truss::methods {

namespace {

using S = SweepOptions;
using campaign::SweepVariable;

// Candidates per bracket: 20 place the crossing to 5 % of the bracket, well below what the
// estimates' scatter resolves at the runs a value takes.
constexpr int kMaxRefine = 20;

bool is_nominal(const S& s) { return s.axis.variable == SweepVariable::nominal; }
bool is_spread(const S& s) { return s.axis.variable == SweepVariable::spread; }
bool refines(const S& s) { return s.axis.refine > 0; }

campaign::OptionRow<S> variable_row(std::string_view key, SweepVariable v, std::string_view doc) {
  campaign::OptionRow<S> r{{key, campaign::OptionKind::text, "", {}, doc}};
  r.get_text = [](const S& s) { return s.axis.key; };
  r.set_text = v == SweepVariable::nominal ? +[](S& s, const std::string& k) {
    s.axis.variable = SweepVariable::nominal;
    s.axis.key = k;
  } : +[](S& s, const std::string& k) {
    s.axis.variable = SweepVariable::spread;
    s.axis.key = k;
  };
  r.written = v == SweepVariable::nominal ? &is_nominal : &is_spread;
  return r;
}

// safe_side: "above" (+1) or "below" (-1); written when given.
campaign::OptionRow<S> safe_side_row() {
  campaign::OptionRow<S> r{{"safe_side", campaign::OptionKind::choice, "", {},
                            "where p falls: above (larger values are safer; the allowable is a least value) or "
                            "below; a key sweep must give it, a spread sweep's is below",
                            {"above", "below"}}};
  r.set_int = [](S& s, std::int64_t i) { s.declared_side = i == 0 ? +1 : -1; };
  r.get_int = [](const S& s) -> std::int64_t { return s.declared_side > 0 ? 0 : 1; };
  r.written = [](const S& s) { return s.declared_side != 0; };
  return r;
}

// The rules between the keys, once each is read: key or spread; values, or from, to and count.
void check_sweep_keys(const campaign::TomlSource& c, const toml::table& t, SweepOptions& s) {
  const toml::node *key = t.get("key"), *spread = t.get("spread"), *values = t.get("values"), *from = t.get("from"),
                   *to = t.get("to"), *count = t.get("count");
  if ((key != nullptr) == (spread != nullptr))
    c.fail(key ? key : spread ? spread : &t,
           "sweep: give either key = \"<scene key>\" (its nominal value is swept) or spread = \"<dispersed key>\" "
           "(that dispersion's std or half-width is swept)");
  if (key && !t.get("safe_side"))
    c.fail(key, fmt::format("sweep.safe_side: a sweep of {}'s nominal value must say on which side the failure "
                            "probability falls (it is not guessed from the estimates): safe_side = \"above\" "
                            "(larger values are safer: the allowable is a least value) or \"below\"",
                            s.axis.key));
  if (values && (from || to || count))
    c.fail(from ? from : to ? to : count, "sweep: give values = [...] or from, to and count, not both");
  if (values) return;
  if (!from || !to || !count)
    c.fail(from ? from : to ? to : count ? count : &t, "sweep: give values = [...] or all of from, to and count");
  const S::Grid& g = s.grid;
  if (!(g.from < g.to)) c.fail(from, fmt::format("sweep.from: must be below sweep.to, got {} and {}", g.from, g.to));
  for (std::int64_t i = 0; i < g.count; ++i)
    s.axis.values.push_back(i == g.count - 1 ? g.to
                                             : g.from + (g.to - g.from) * static_cast<double>(i) /
                                                            static_cast<double>(g.count - 1));
}

}  // namespace

const campaign::OptionTable<S>& SweepOptions::table() {
  using campaign::kAnyNumber;
  using campaign::never_written;
  static const campaign::OptionTable<S> t{
      "sweep", "a design sweep: the [failure] event's probability at each value of one design variable, and the "
               "allowable", {
          variable_row("key", SweepVariable::nominal, "a real scene key: its nominal value takes each value"),
          variable_row("spread", SweepVariable::spread,
                       "or: the dispersed key whose spread takes each value (std, sigma, or uniform half-width)"),
          TRUSS_OPTION_REALS(S, "values", axis.values, "the variable's", "the design values, strictly ascending"),
          written_if(TRUSS_OPTION_REAL(S, "from", grid.from, "the variable's", kAnyNumber,
                                       "or: the first of count evenly spaced values"), &never_written<S>),
          written_if(TRUSS_OPTION_REAL(S, "to", grid.to, "the variable's", kAnyNumber, "the last of them"),
                     &never_written<S>),
          written_if(TRUSS_OPTION_INT(S, "count", grid.count, "1", campaign::closed_range(2, 1000), "how many"),
                     &never_written<S>),
          required(TRUSS_OPTION_REAL(S, "target_probability", target_probability, "1", campaign::open_range(0, 1),
                                     "the failure probability the allowable keeps, e.g. 1e-6")),
          TRUSS_OPTION_REAL(S, "confidence", confidence, "1", campaign::open_range(0.5, 1),
                            "of the one-sided upper bound on p"),
          safe_side_row(),
          written_if(TRUSS_OPTION_INT(S, "refine", axis.refine, "1", campaign::closed_range(0, kMaxRefine),
                                      "then this many more values inside the bracket of the allowable"),
                     &refines),
      }};
  return t;
}

std::unique_ptr<campaign::MethodOptions> SweepOptions::parse(const campaign::MethodInput& in) {
  auto o = std::make_unique<SweepOptions>();
  campaign::read_method_table(in, table(), *o);
  check_sweep_keys(in.source, *in.table, *o);
  o->inner = campaign::read_method_choice(in);
  return o;
}

std::string SweepOptions::validate(const campaign::CampaignOptions& c) const {
  if (std::string e = campaign::check_option_ranges(table(), *this, "sweep."); !e.empty()) return e;
  const campaign::FailureOptions* f = inner.options().failure_event();
  if (f == nullptr)
    return fmt::format("ensemble.method: \"{}\" estimates no failure probability: a sweep runs, at each value, a "
                       "method with a [failure] event (subset simulation, Monte Carlo, [ensemble.stop])",
                       inner.name());
  if (f->kind == campaign::FailureKind::none)
    return "failure: a sweep estimates the probability of a [failure] event at each value: add [failure] (margin = "
           "\"rail_margin_m\", or column = \"peak_drive_torque_Nm\", above = 0.02, unit = \"N m\")";
  if (c.dispersions.empty()) return "sweep: a failure probability needs at least one [[dispersion]]";
  if (inner.name() == "importance")
    if (std::string e = validate_reweighted_sweep(c, *this); !e.empty()) return e;
  return inner.options().validate(campaign::calc_campaign_at(c, 0));
}

int SweepOptions::calc_safe_side() const {
  if (declared_side != 0) return declared_side;
  return is_spread(*this) ? -1 : 0;
}

std::string SweepOptions::to_toml() const {
  return inner.options().to_toml() + "[sweep]\n" + campaign::write_options(table(), *this) + "\n";
}

std::int64_t SweepOptions::calc_max_runs(const campaign::CampaignOptions& c) const {
  if (inner.name() == "importance") return inner.options().calc_max_runs(c);  // one set of runs serves every value
  return inner.options().calc_max_runs(c) * static_cast<std::int64_t>(campaign::calc_max_design_values(axis));
}

std::string SweepOptions::describe_max_runs(const campaign::CampaignOptions& c) const {
  const std::string d = inner.options().describe_max_runs(c);
  if (inner.name() == "importance") return d + fmt::format(" for all {} sweep.values", axis.n_values());
  if (axis.refine == 0) return fmt::format("{} at each of the {} sweep.values", d, axis.n_values());
  return fmt::format("{} at each of the {} sweep.values and sweep.refine = {}", d, axis.n_values(), axis.refine);
}

}  // namespace truss::methods
