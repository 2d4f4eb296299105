// [sweep] of a campaign file (sweep.hpp): parsed, checked, written back, and each value's campaign.
#include "campaign/sweep.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/dispersion.hpp"
#include "campaign/failure.hpp"
#include "campaign/toml_read.hpp"
#include "sampling/sampling.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

namespace {

constexpr std::uint64_t kTagSweep = 0x5357454550ULL;  // "SWEEP": the per-value seeds
// Candidates per bracket: 20 place the crossing to 5 % of the bracket, well below what the
// estimates' scatter resolves at the runs a value takes.
constexpr int kMaxRefine = 20;

// The spread parameter a spread sweep sets, by distribution; nullptr for a discrete table.
const char* spread_name(DistributionKind k) {
  switch (k) {
    case DistributionKind::normal:
    case DistributionKind::truncated_normal: return "std";
    case DistributionKind::lognormal: return "sigma";
    case DistributionKind::uniform: return "half_width";
    case DistributionKind::discrete: return nullptr;
  }
  return nullptr;
}

void set_spread(DispersionOptions& d, double v) {
  if (d.distribution == DistributionKind::lognormal) d.sigma = v;
  else if (d.distribution == DistributionKind::uniform) {
    const double centre = 0.5 * (d.lower + d.upper);
    d.lower = centre - v;
    d.upper = centre + v;
  } else d.std = v;
}

double get_spread(const DispersionOptions& d) {
  if (d.distribution == DistributionKind::lognormal) return d.sigma;
  if (d.distribution == DistributionKind::uniform) return 0.5 * (d.upper - d.lower);
  return d.std;
}

std::string toml_num(double v) {
  std::string t = fmt::format("{}", v);
  if (t.find_first_of(".eEni") == std::string::npos) t += ".0";
  return t;
}

// Which method estimates p at each value, or why none can.
// (The stop rule's own: StopOptions::validate refuses a percentile target in a sweep.)
std::string check_inner_method(const CampaignOptions& c) {
  const EnsembleOptions& e = c.ensemble;
  const FailureOptions* f = e.method.options().failure_event();
  if (f == nullptr)
    return fmt::format("ensemble.method: \"{}\" estimates no failure probability: a sweep's inner method is subset "
                       "simulation (ensemble.method = \"subset\"), Monte Carlo or [ensemble.stop]", e.method.name());
  if (f->kind == FailureKind::none)
    return "failure: a sweep estimates the probability of a [failure] event at each value: add [failure] (margin = "
           "\"rail_margin_m\", or column = \"peak_drive_torque_Nm\", above = 0.02, unit = \"N m\")";
  if (std::string err = validate_failure_column(*f); !err.empty()) return err;
  if (c.dispersions.empty()) return "sweep: a failure probability needs at least one [[dispersion]]";
  if (e.sampling != SamplingMethod::monte_carlo)
    return fmt::format("ensemble.sampling: \"{}\" gives no binomial interval of a probability: a sweep's inner "
                       "method is subset simulation (ensemble.method = \"subset\"), Monte Carlo or [ensemble.stop]",
                       to_string(e.sampling));
  return {};
}

// The design variable itself: a real scene key (nominal) or a dispersion with a spread.
std::string check_variable(const CampaignOptions& c) {
  const SweepOptions& s = c.sweep;
  if (s.variable == SweepVariable::spread) {
    const int i = find_sweep_dispersion(c);
    if (i < 0)
      return fmt::format("sweep.spread: \"{}\" is not the key of a [[dispersion]] of this campaign", s.key);
    if (!spread_name(c.dispersions[static_cast<std::size_t>(i)].distribution))
      return fmt::format("sweep.spread: the dispersion of \"{}\" is a discrete table, which has no spread", s.key);
    return {};
  }
  const sim::SceneKey* k = sim::find_scene_key(s.key);
  if (!k || (k->kind != sim::KeyKind::real && k->kind != sim::KeyKind::opt_real) || !k->set_real || !k->get_real)
    return fmt::format("sweep.key: \"{}\" is not a real-valued scene key (e.g. drive.stall_torque_Nm, rail.beta_deg, "
                       "mast.diagonal_free_length_m)", s.key);
  for (const DispersionOptions& d : c.dispersions)
    if (d.key == s.key && d.apply == Apply::absolute)
      return fmt::format("sweep.key: \"{}\" is dispersed with apply = \"absolute\", which ignores its nominal value; "
                         "sweep its spread (sweep.spread) or disperse it relative or offset", s.key);
  return {};
}

// Each value: in the key's hard range, a scene the model takes, plausible dispersions.
std::string check_values(const CampaignOptions& c) {
  const SweepOptions& s = c.sweep;
  if (s.values.size() < 2)
    return fmt::format("sweep.values: a sweep needs at least 2 values, got {}", s.values.size());
  for (std::size_t k = 0; k < s.values.size(); ++k) {
    const double v = s.values[k];
    if (!std::isfinite(v)) return fmt::format("sweep.values: value {} is not finite", k + 1);
    if (k > 0 && !(v > s.values[k - 1]))
      return fmt::format("sweep.values: must be strictly ascending, got {} after {}", v, s.values[k - 1]);
    if (s.variable == SweepVariable::spread && !(v > 0.0))
      return fmt::format("sweep.values: a spread must be positive, got {}", v);
    if (s.variable == SweepVariable::nominal)
      if (std::string e = sim::check_hard_range(*sim::find_scene_key(s.key), v); !e.empty())
        return "sweep.values: " + e;
  }
  // Every value the sweep can run: the listed ones and the refinement's candidates between them.
  for (std::size_t k = 0; k < s.n_design_values(); ++k) {
    const double v = s.find_value(k);
    const CampaignOptions at = calc_campaign_at(c, k);
    std::string why = at.base.validate();
    if (why.empty()) {
      try {
        why = sim::validate_mast(sim::build_mast(at.base), at.base);
      } catch (const std::exception& e) {
        why = e.what();
      }
    }
    // A candidate is named as such: the user wrote its neighbours, not it.
    const std::string field = k < s.n_values() ? "sweep.values" : "sweep.refine";
    const std::string at_v = k < s.n_values() ? fmt::format("{} = {}", sweep_variable_name(c), v)
                                              : fmt::format("the candidate {} = {}", sweep_variable_name(c), v);
    if (!why.empty())
      return fmt::format("{}: {} {} gives a scene the model refuses: {}", field, at_v, sweep_variable_units(c), why);
    for (std::size_t i = 0; i < at.dispersions.size(); ++i) {
      const std::string e = make_distribution(at.dispersions[i]).validate();
      if (!e.empty()) return fmt::format("{}: at {}: dispersion[{}]: {}", field, at_v, i + 1, e);
      if (std::string d = check_dispersion_draws(at, i); !d.empty())
        return fmt::format("{}: at {}: dispersion[{}]: {}", field, at_v, i + 1, d);
    }
  }
  return {};
}

}  // namespace

int find_sweep_dispersion(const CampaignOptions& c) {
  if (!c.sweep.active || c.sweep.variable != SweepVariable::spread) return -1;
  for (std::size_t i = 0; i < c.dispersions.size(); ++i)
    if (c.dispersions[i].key == c.sweep.key) return static_cast<int>(i);
  return -1;
}

std::string sweep_variable_name(const CampaignOptions& c) {
  const int i = find_sweep_dispersion(c);
  if (i < 0) return c.sweep.key;
  const char* n = spread_name(c.dispersions[static_cast<std::size_t>(i)].distribution);
  return c.sweep.key + " " + (n ? n : "spread");
}

std::string sweep_variable_units(const CampaignOptions& c) {
  const int i = find_sweep_dispersion(c);
  if (i < 0) return find_key_units(c.sweep.key);
  const DispersionOptions& d = c.dispersions[static_cast<std::size_t>(i)];
  // A relative draw and a lognormal's sigma are fractions; absolute and offset draws are in the key's unit.
  if (d.apply == Apply::relative || d.distribution == DistributionKind::lognormal) return "1";
  return find_key_units(d.key);
}

double calc_sweep_own_value(const CampaignOptions& c) {
  const int i = find_sweep_dispersion(c);
  if (i >= 0) return get_spread(c.dispersions[static_cast<std::size_t>(i)]);
  const sim::SceneKey* k = sim::find_scene_key(c.sweep.key);
  return k && k->get_real ? k->get_real(c.base) : std::nan("");
}

double SweepOptions::find_value(std::size_t k) const {
  const std::size_t n = values.size();
  if (k < n) return values[k];
  const std::size_t m = static_cast<std::size_t>(refine), i = (k - n) / m, j = (k - n) % m;
  const double a = values.at(i), b = values.at(i + 1);
  return a + static_cast<double>(j + 1) * (b - a) / static_cast<double>(m + 1);
}

std::uint64_t calc_sweep_seed(std::uint64_t master_seed, std::size_t k) {
  return sampling::splitmix_at(master_seed ^ kTagSweep, static_cast<std::uint64_t>(k)) >> 1;
}

CampaignOptions calc_campaign_at(const CampaignOptions& c, std::size_t k) {
  CampaignOptions at = c;
  at.sweep = SweepOptions{};
  at.ensemble.master_seed = calc_sweep_seed(c.ensemble.master_seed, k);
  if (k >= c.sweep.n_design_values()) throw std::out_of_range(fmt::format("sweep: no design value {}", k));
  const double v = c.sweep.find_value(k);
  if (const int i = find_sweep_dispersion(c); i >= 0) {
    set_spread(at.dispersions[static_cast<std::size_t>(i)], v);
  } else if (const sim::SceneKey* key = sim::find_scene_key(c.sweep.key); key && key->set_real) {
    key->set_real(at.base, v);
  }
  return at;
}

std::string validate_sweep(const CampaignOptions& c) {
  const SweepOptions& s = c.sweep;
  if (!s.active) return {};
  if (!(s.target_probability > 0.0 && s.target_probability < 1.0))
    return fmt::format("sweep.target_probability: must lie in (0, 1), got {}", s.target_probability);
  if (!(s.confidence > 0.5 && s.confidence < 1.0))
    return fmt::format("sweep.confidence: must lie in (0.5, 1), got {}", s.confidence);
  if (s.refine < 0 || s.refine > kMaxRefine)
    return fmt::format("sweep.refine: must lie in [0, {}], got {}", kMaxRefine, s.refine);
  if (std::string e = check_inner_method(c); !e.empty()) return e;
  if (std::string e = check_variable(c); !e.empty()) return e;
  return check_values(c);
}

std::string sweep_toml(const SweepOptions& s) {
  if (!s.active) return {};
  std::string t = fmt::format("[sweep]\n{} = \"{}\"\nvalues = [",
                              s.variable == SweepVariable::spread ? "spread" : "key", s.key);
  for (std::size_t i = 0; i < s.values.size(); ++i) t += (i ? ", " : "") + toml_num(s.values[i]);
  t += fmt::format("]\ntarget_probability = {}\nconfidence = {}\n", toml_num(s.target_probability),
                   toml_num(s.confidence));
  if (s.refine > 0) t += fmt::format("refine = {}\n", s.refine);
  return t + "\n";
}

namespace detail {

void parse_sweep_table(const Ctx& c, const toml::table& t, CampaignOptions& o) {
  SweepOptions& s = o.sweep;
  s.active = true;
  s.line = static_cast<int>(t.source().begin.line);
  const toml::node *key = t.get("key"), *spread = t.get("spread"), *values = t.get("values"), *from = t.get("from"),
                   *to = t.get("to"), *count = t.get("count");
  for (const auto& [k, v] : t)
    if (k != "key" && k != "spread" && k != "values" && k != "from" && k != "to" && k != "count" &&
        k != "target_probability" && k != "confidence" && k != "refine")
      c.fail(&v, fmt::format("unknown key 'sweep.{}' (known: sweep.key, sweep.spread, sweep.values, sweep.from, "
                             "sweep.to, sweep.count, sweep.target_probability, sweep.confidence, sweep.refine)",
                             k.str()));
  if ((key != nullptr) == (spread != nullptr))
    c.fail(key ? key : spread ? spread : &t,
           "sweep: give either key = \"<scene key>\" (its nominal value is swept) or spread = \"<dispersed key>\" "
           "(that dispersion's std or half-width is swept)");
  s.variable = key ? SweepVariable::nominal : SweepVariable::spread;
  s.key = get_string(c, key ? *key : *spread, key ? "sweep.key" : "sweep.spread");
  if (values && (from || to || count))
    c.fail(from ? from : to ? to : count, "sweep: give values = [...] or from, to and count, not both");
  if (values) {
    const toml::array* a = values->as_array();
    if (!a) c.fail(values, "sweep.values: expected an array of numbers");
    for (const auto& v : *a) s.values.push_back(get_number(c, v, "sweep.values"));
  } else {
    if (!from || !to || !count)
      c.fail(from ? from : to ? to : count ? count : &t, "sweep: give values = [...] or all of from, to and count");
    const double a = get_number(c, *from, "sweep.from"), b = get_number(c, *to, "sweep.to");
    const std::int64_t n = get_integer(c, *count, "sweep.count");
    if (n < 2 || n > 1000) c.fail(count, fmt::format("sweep.count: must lie in [2, 1000], got {}", n));
    if (!(a < b)) c.fail(from, fmt::format("sweep.from: must be below sweep.to, got {} and {}", a, b));
    for (std::int64_t i = 0; i < n; ++i)
      s.values.push_back(i == n - 1 ? b : a + (b - a) * static_cast<double>(i) / static_cast<double>(n - 1));
  }
  const toml::node* target = t.get("target_probability");
  if (!target) c.fail(&t, "sweep.target_probability: missing (the failure probability the allowable keeps, e.g. 1e-6)");
  s.target_probability = get_number(c, *target, "sweep.target_probability");
  if (const toml::node* conf = t.get("confidence")) s.confidence = get_number(c, *conf, "sweep.confidence");
  if (const toml::node* refine = t.get("refine")) {
    const std::int64_t m = get_integer(c, *refine, "sweep.refine");
    if (m < 0 || m > kMaxRefine)
      c.fail(refine, fmt::format("sweep.refine: must lie in [0, {}], got {}", kMaxRefine, m));
    s.refine = static_cast<int>(m);
  }
}

}  // namespace detail
}  // namespace truss::campaign
