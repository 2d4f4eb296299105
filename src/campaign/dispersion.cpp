#include "campaign/dispersion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "campaign/design_axis.hpp"
#include "sim/scene_keys.hpp"

namespace truss::campaign {

// Every key-specific step goes through the scene key table (sim/scene_keys.hpp).
double find_nominal(const sim::SceneOptions& s, const std::string& k) {
  const sim::SceneKey* key = sim::find_scene_key(k);
  if (!key || !key->is_dispersible()) return std::numeric_limits<double>::quiet_NaN();
  return key->get_real(s);
}

std::string find_key_units(const std::string& k) {
  const sim::SceneKey* key = sim::find_scene_key(k);
  return key ? std::string(key->unit) : "1";
}

namespace {

double applied(Apply how, double nominal_value, double draw) {
  switch (how) {
    case Apply::absolute: return draw;
    case Apply::relative: return nominal_value * (1.0 + draw);
    case Apply::offset: return nominal_value + draw;
  }
  return draw;
}

// Each of the run's bays (frames) k < drawn: field(k) (the built mast's nominal) takes the draw
// vals[k], and vals[k] the applied value. The kind of application is a template argument so that
// the loop does not look it up again after each (indirect) field access.
template <Apply How, class Field>
void apply_draws(Field field, double* vals, int drawn) {
  for (int k = 0; k < drawn; ++k) {
    double* f = field(static_cast<std::size_t>(k));
    *f = applied(How, *f, vals[k]);
    vals[k] = *f;
  }
}

template <class Field>
void apply_draws(Apply how, Field field, double* vals, int drawn) {
  switch (how) {
    case Apply::absolute: return apply_draws<Apply::absolute>(field, vals, drawn);
    case Apply::relative: return apply_draws<Apply::relative>(field, vals, drawn);
    case Apply::offset: return apply_draws<Apply::offset>(field, vals, drawn);
  }
}

}  // namespace

Distribution make_distribution(const DispersionOptions& d) {
  if (d.distribution == DistributionKind::normal) return Distribution::normal(d.mean, d.std);
  if (d.distribution == DistributionKind::truncated_normal)
    return Distribution::truncated_normal(d.mean, d.std, d.lower, d.upper);
  if (d.distribution == DistributionKind::uniform) return Distribution::uniform(d.lower, d.upper);
  if (d.distribution == DistributionKind::lognormal) return Distribution::lognormal(d.mu, d.sigma);
  std::vector<double> w = d.weights;
  if (w.empty()) w.assign(d.values.size(), 1.0);
  return Distribution::discrete(d.values, w);
}

DimensionLayout calc_layout(const CampaignOptions& c) {
  DimensionLayout L;
  L.n_bays_max = c.base.mast.n_bays;
  for (const auto& d : c.dispersions)
    if (d.key == "mast.n_bays")
      for (double v : d.values) L.n_bays_max = std::max(L.n_bays_max, static_cast<int>(v));
  L.strut_inertia_follows =
      !c.base.mast.strut_inertia_kg_m2.has_value() &&
      std::none_of(c.dispersions.begin(), c.dispersions.end(),
                   [](const DispersionOptions& d) { return d.key == "mast.strut_inertia_kg_m2"; });
  for (const auto& d : c.dispersions) {
    const int n = d.per == Per::run ? 1 : d.per == Per::bay ? L.n_bays_max : L.n_bays_max + 1;
    L.offset.push_back(L.total);
    L.count.push_back(n);
    L.total += n;
    L.distributions.push_back(make_distribution(d));
    L.keys.push_back(sim::find_scene_key(d.key));
    const std::string e = L.distributions.back().validate();
    if (!e.empty()) throw std::invalid_argument("dispersion of " + d.key + ": " + e);
  }
  if (const DesignAxis* axis = find_design_axis(c)) {
    L.design = L.total++;
    L.n_design_values = axis->n_design_values();
    L.sweep_dispersion = find_sweep_dispersion(c);
    if (L.sweep_dispersion < 0) {
      L.sweep_key = sim::find_scene_key(axis->key);
    } else {
      CampaignOptions at = c;
      for (std::size_t k = 0; k < axis->n_design_values(); ++k) {
        apply_design_value(c, k, at);
        const std::size_t d = static_cast<std::size_t>(L.sweep_dispersion);
        L.sweep_distributions.push_back(make_distribution(at.dispersions[d]));
      }
    }
  }
  return L;
}

namespace {
// The 3-sigma quantiles: tolerances are stated at 3 sigma, and a campaign of a few thousand runs
// draws about that far into each tail.
constexpr double kPlausibleLow = 0.00135, kPlausibleHigh = 0.99865;
// A length's relative or offset draws move it at most this share of its nominal value: real
// tolerances are a few per cent (+-0.5 mm on 0.18 m struts is 0.3 %, the shipped diagonal cut
// lengths 3 % at 3 sigma); past it the draw is a unit slip (millimetres typed as metres).
constexpr double kMaxLengthShare = 0.2;

// A draw the plausibility check makes: its uniform and how the message names it.
struct PlausibleDraw {
  double u;
  std::string where;
};

// The draws of interest: a uniform's two ends (every draw lies between them), the two 3-sigma
// quantiles of an unbounded or truncated distribution, every value of a discrete table (its
// uniform the middle of its probability).
std::vector<PlausibleDraw> plausible_draws(const Distribution& dist) {
  std::vector<PlausibleDraw> out;
  if (dist.kind == DistributionKind::uniform) {
    out.push_back({0.0, fmt::format("its lower end, a draw of {:.6g},", dist.calc_quantile(0.0))});
    out.push_back({1.0, fmt::format("its upper end, a draw of {:.6g},", dist.calc_quantile(1.0))});
  } else if (dist.kind != DistributionKind::discrete) {
    for (double level : {kPlausibleLow, kPlausibleHigh})
      out.push_back({level, fmt::format("its {} % quantile ({}3 sigma), a draw of {:.6g},", 100.0 * level,
                                        level < 0.5 ? "-" : "+", dist.calc_quantile(level))});
  } else {
    double total = 0.0, below = 0.0;
    for (double w : dist.weights) total += w;
    for (std::size_t k = 0; k < dist.weights.size(); ++k) {
      out.push_back({(below + 0.5 * dist.weights[k]) / total, fmt::format("its value {}", dist.values[k])});
      below += dist.weights[k];
    }
  }
  return out;
}

// A length (a key in m that must be positive) moved by a relative or offset draw past
// kMaxLengthShare of its nominal value: why, else "".
std::string check_length_share(const DispersionOptions& d, double draw, double v) {
  const sim::SceneKey* key = sim::find_scene_key(d.key);
  const bool length = key && key->unit == "m" && key->hard.lo == 0.0 && key->hard.lo_open;
  if (!length || d.apply == Apply::absolute) return {};
  const double nominal = d.apply == Apply::relative ? v / (1.0 + draw) : v - draw;
  const double share = d.apply == Apply::relative ? std::abs(draw) : std::abs(draw / nominal);
  if (!(share > kMaxLengthShare)) return {};
  const std::string slip = d.apply == Apply::offset
                               ? fmt::format(": millimetres typed as metres? {:.6g} mm is {:.6g} m", draw, draw * 1e-3)
                               : ": a percentage typed as a fraction? std = 0.05 is 5 %";
  return fmt::format("a length moved {:.3g} % from its nominal {:.6g} m (a length's draws are refused past {:g} % of "
                     "it{})", 100.0 * share, nominal, 100.0 * kMaxLengthShare, slip);
}

}  // namespace

std::string check_dispersion_draws(const CampaignOptions& c, std::size_t i) {
  const DispersionOptions& d = c.dispersions[i];
  const DimensionLayout L = calc_layout(c);
  const Distribution& dist = L.distributions[i];
  for (const PlausibleDraw& p : plausible_draws(dist)) {
    std::vector<double> u(static_cast<std::size_t>(std::max(1, L.total)), 0.5);  // a sweep: its middle value
    for (int k = 0; k < L.count[i]; ++k) u[static_cast<std::size_t>(L.offset[i] + k)] = p.u;
    std::string why, value, refusal = "which the model refuses", outcome = "most runs would end as invalid input";
    try {
      const RunInputs in = calc_run_inputs(c, L, u.data());
      const double v = in.values[i].front();
      value = fmt::format("{:.6g} {}", v, find_key_units(d.key));
      why = check_length_share(d, dist.calc_quantile(p.u), v);
      if (!why.empty()) {
        refusal = "which no tolerance gives";
        outcome = "the runs would study a mast no drawing describes";
      }
      if (why.empty()) why = in.scene.validate();
      if (why.empty()) why = sim::validate_mast(in.mast, in.scene);
    } catch (const std::exception& e) {
      why = e.what();
    }
    if (why.empty()) continue;
    return fmt::format("{} ({} {}) is implausible: {} gives {} = {}, {} ({}); {}{}", d.key, to_string(d.apply),
                       to_string(d.distribution), p.where, d.key, value.empty() ? "no value" : value, refusal, why,
                       outcome,
                       d.apply == Apply::relative ? " (apply = \"relative\" takes a fraction of the nominal value: "
                                                    "std = 0.05 is 5 %)"
                                                  : "");
  }
  return {};
}

RunInputs calc_run_inputs(const CampaignOptions& c, const DimensionLayout& L, const double* u) {
  RunInputs in;
  in.scene = c.base;
  in.values.resize(c.dispersions.size());
  // A sweep's value: into the base scene (the nominal the draws apply to) or the swept distribution.
  std::size_t sweep_k = 0;
  if (L.design >= 0) {
    sweep_k = L.find_sweep_index(u[L.design], L.n_design_values);
    const double value = find_design_axis(c)->find_value(sweep_k);
    if (L.sweep_key) L.sweep_key->set_real(in.scene, value);
    in.values.push_back({value});
  }
  std::optional<sim::SceneOptions> swept;
  if (L.sweep_key) swept = in.scene;
  const sim::SceneOptions& base = swept ? *swept : c.base;
  auto dist = [&](std::size_t i) -> const Distribution& {
    return static_cast<int>(i) == L.sweep_dispersion ? L.sweep_distributions[sweep_k] : L.distributions[i];
  };
  // Per-run draws first (the bay count among them), then the mast is built and dispersed.
  for (std::size_t i = 0; i < c.dispersions.size(); ++i) {
    const auto& d = c.dispersions[i];
    if (d.per != Per::run) continue;
    const sim::SceneKey* key = L.keys[i];
    const double nominal =
        key && key->is_dispersible() ? key->get_real(base) : std::numeric_limits<double>::quiet_NaN();
    const double v = applied(d.apply, nominal, dist(i).calc_quantile(u[L.offset[i]]));
    in.values[i] = {v};
    if (key && key->set_real) key->set_real(in.scene, v);
  }
  in.mast = sim::build_mast(in.scene);
  const int n = in.mast.n_bays();
  for (std::size_t i = 0; i < c.dispersions.size(); ++i) {
    const auto& d = c.dispersions[i];
    if (d.per == Per::run) continue;
    // The draws of the run's bays (frames) in bulk, into the values, then applied in place.
    auto& vals = in.values[i];
    vals.assign(static_cast<std::size_t>(L.count[i]), std::numeric_limits<double>::quiet_NaN());
    const int drawn = d.per == Per::bay ? n : n + 1;
    dist(i).calc_quantiles(u + L.offset[i], vals.data(), static_cast<std::size_t>(drawn));
    const sim::SceneKey& key = *L.keys[i];
    if (d.per == Per::bay)
      apply_draws(d.apply, [&](std::size_t k) { return key.bay_field(in.mast.bays[k]); }, vals.data(), drawn);
    else
      apply_draws(d.apply, [&](std::size_t k) { return key.frame_field(in.mast.frames[k]); }, vals.data(), drawn);
  }
  // A dispersed strut mass or length keeps the slender-rod inertia unless J_c is set or dispersed.
  if (L.strut_inertia_follows)
    for (auto& b : in.mast.bays)
      b.strut_inertia_kg_m2 = model::calc_default_strut_inertia_kg_m2(b.strut_mass_kg, b.strut_length_m);
  return in;
}

}  // namespace truss::campaign
