// A sweep's design axis as the campaign sees it (design_axis.hpp): each value applied, checked, and
// each value's campaign.
#include "campaign/design_axis.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "campaign/campaign.hpp"
#include "campaign/dispersion.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

namespace {


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

// The design variable itself: a real scene key (nominal) or a dispersion with a spread.
std::string check_variable(const CampaignOptions& c) {
  const DesignAxis& s = *find_design_axis(c);
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
  const DesignAxis& s = *find_design_axis(c);
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

const DesignAxis* find_design_axis(const CampaignOptions& c) {
  return c.ensemble.method ? c.ensemble.method.options().design_axis() : nullptr;
}

int find_sweep_dispersion(const CampaignOptions& c) {
  const DesignAxis* a = find_design_axis(c);
  if (a == nullptr || a->variable != SweepVariable::spread) return -1;
  for (std::size_t i = 0; i < c.dispersions.size(); ++i)
    if (c.dispersions[i].key == a->key) return static_cast<int>(i);
  return -1;
}

std::string sweep_variable_name(const CampaignOptions& c) {
  const std::string& key = find_design_axis(c)->key;
  const int i = find_sweep_dispersion(c);
  if (i < 0) return key;
  const char* n = spread_name(c.dispersions[static_cast<std::size_t>(i)].distribution);
  return key + " " + (n ? n : "spread");
}

std::string sweep_variable_units(const CampaignOptions& c) {
  const int i = find_sweep_dispersion(c);
  if (i < 0) return find_key_units(find_design_axis(c)->key);
  const DispersionOptions& d = c.dispersions[static_cast<std::size_t>(i)];
  // A relative draw and a lognormal's sigma are fractions; absolute and offset draws are in the key's unit.
  if (d.apply == Apply::relative || d.distribution == DistributionKind::lognormal) return "1";
  return find_key_units(d.key);
}

double calc_sweep_own_value(const CampaignOptions& c) {
  const int i = find_sweep_dispersion(c);
  if (i >= 0) return get_spread(c.dispersions[static_cast<std::size_t>(i)]);
  const sim::SceneKey* k = sim::find_scene_key(find_design_axis(c)->key);
  return k && k->get_real ? k->get_real(c.base) : std::nan("");
}

double DesignAxis::find_value(std::size_t k) const {
  const std::size_t n = values.size();
  if (k < n) return values[k];
  const std::size_t m = static_cast<std::size_t>(refine), i = (k - n) / m, j = (k - n) % m;
  const double a = values.at(i), b = values.at(i + 1);
  return a + static_cast<double>(j + 1) * (b - a) / static_cast<double>(m + 1);
}

void apply_design_value(const CampaignOptions& c, std::size_t k, CampaignOptions& at) {
  const DesignAxis& a = *find_design_axis(c);
  if (k >= a.n_design_values()) throw std::out_of_range(fmt::format("sweep: no design value {}", k));
  const double v = a.find_value(k);
  if (const int i = find_sweep_dispersion(c); i >= 0) {
    set_spread(at.dispersions[static_cast<std::size_t>(i)], v);
  } else if (const sim::SceneKey* key = sim::find_scene_key(a.key); key && key->set_real) {
    key->set_real(at.base, v);
  }
}

CampaignOptions calc_campaign_at(const CampaignOptions& c, std::size_t k) {
  CampaignOptions at = c;
  apply_design_value(c, k, at);
  at.ensemble.method = *c.ensemble.method.options().inner_method();
  // The file's master seed at every value: common random numbers (design_axis.hpp).
  return at;
}

std::string validate_design_axis(const CampaignOptions& c) {
  if (find_design_axis(c) == nullptr) return {};
  if (std::string e = check_variable(c); !e.empty()) return e;
  return check_values(c);
}

}  // namespace truss::campaign
