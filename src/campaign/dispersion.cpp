#include "campaign/dispersion.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace truss::campaign {

double find_nominal(const sim::SceneOptions& s, const std::string& k) {
  const auto& m = s.mast;
  if (k == "mast.n_bays") return m.n_bays;
  if (k == "mast.strut_length_m") return m.strut_length_m;
  if (k == "mast.strut_mass_kg") return m.strut_mass_kg;
  if (k == "mast.strut_inertia_kg_m2") return m.strut_inertia_kg_m2.value_or(m.strut_mass_kg * m.strut_length_m * m.strut_length_m / 12.0);
  if (k == "mast.frame_side_m") return m.frame_side_m;
  if (k == "mast.frame_mass_kg") return m.frame_mass_kg;
  if (k == "mast.diagonal_stiffness_N_per_m") return m.diagonal_stiffness_N_per_m;
  if (k == "mast.diagonal_free_length_m") return m.diagonal_free_length_m;
  if (k == "mast.tip_mass_kg") return m.tip_mass_kg.value_or(6.0 * m.strut_mass_kg + m.frame_mass_kg);
  if (k == "rail.x_m") return s.rail.x_m;
  if (k == "rail.y_m") return s.rail.y_m;
  if (k == "rail.beta_deg") return s.rail.beta_deg;
  if (k == "drive.speed_m_per_s") return s.drive.speed_m_per_s;
  if (k == "drive.screw_lead_m") return s.drive.screw_lead_m;
  if (k == "drive.torque_Nm") return s.drive.torque_Nm;
  if (k == "drive.stall_torque_Nm") return s.drive.stall_torque_Nm;
  if (k == "drive.no_load_speed_rad_per_s") return s.drive.no_load_speed_rad_per_s;
  if (k == "panels.length_m") return s.panels.length_m;
  if (k == "panels.mass_kg") return s.panels.mass_kg;
  if (k == "panels.tip_height_m") return s.panels.tip_height_m.value_or(2.0 * s.mast.strut_length_m);
  return std::numeric_limits<double>::quiet_NaN();
}

std::string find_key_units(const std::string& key) {
  static const std::pair<const char*, const char*> suffixes[] = {
      {"_N_per_m", "N/m"}, {"_kg_m2", "kg m^2"}, {"_m_per_s", "m/s"}, {"_rad_per_s", "rad/s"}, {"_Nm", "Nm"},
      {"_kg", "kg"}, {"_deg", "deg"}, {"_m", "m"}, {"_s", "s"}, {"_N", "N"}};
  for (const auto& [suffix, units] : suffixes) {
    const std::string s(suffix);
    if (key.size() > s.size() && key.compare(key.size() - s.size(), s.size(), s) == 0) return units;
  }
  return "1";
}

namespace {

void set_run_key(sim::SceneOptions& s, const std::string& k, double v) {
  auto& m = s.mast;
  if (k == "mast.n_bays") m.n_bays = static_cast<int>(std::lround(v));
  else if (k == "mast.tip_mass_kg") m.tip_mass_kg = v;
  else if (k == "rail.x_m") s.rail.x_m = v;
  else if (k == "rail.y_m") s.rail.y_m = v;
  else if (k == "rail.beta_deg") s.rail.beta_deg = v;
  else if (k == "drive.speed_m_per_s") s.drive.speed_m_per_s = v;
  else if (k == "drive.screw_lead_m") s.drive.screw_lead_m = v;
  else if (k == "drive.torque_Nm") s.drive.torque_Nm = v;
  else if (k == "drive.stall_torque_Nm") s.drive.stall_torque_Nm = v;
  else if (k == "drive.no_load_speed_rad_per_s") s.drive.no_load_speed_rad_per_s = v;
  else if (k == "panels.length_m") s.panels.length_m = v;
  else if (k == "panels.mass_kg") s.panels.mass_kg = v;
  else if (k == "panels.tip_height_m") s.panels.tip_height_m = v;
  // per-run values of per-bay / per-frame keys go to the scene too (build_mast spreads them)
  else if (k == "mast.strut_length_m") m.strut_length_m = v;
  else if (k == "mast.strut_mass_kg") m.strut_mass_kg = v;
  else if (k == "mast.strut_inertia_kg_m2") m.strut_inertia_kg_m2 = v;
  else if (k == "mast.frame_side_m") m.frame_side_m = v;
  else if (k == "mast.frame_mass_kg") m.frame_mass_kg = v;
  else if (k == "mast.diagonal_stiffness_N_per_m") m.diagonal_stiffness_N_per_m = v;
  else if (k == "mast.diagonal_free_length_m") m.diagonal_free_length_m = v;
}

double* bay_field(model::BayParams& b, const std::string& k) {
  if (k == "mast.strut_length_m") return &b.strut_length_m;
  if (k == "mast.strut_mass_kg") return &b.strut_mass_kg;
  if (k == "mast.strut_inertia_kg_m2") return &b.strut_inertia_kg_m2;
  if (k == "mast.diagonal_stiffness_N_per_m") return &b.diagonal_stiffness_N_per_m;
  return &b.diagonal_free_length_m;
}

double* frame_field(model::FrameParams& f, const std::string& k) {
  return k == "mast.frame_side_m" ? &f.side_m : &f.mass_kg;
}

double applied(const DispersionOptions& d, double nominal_value, double draw) {
  switch (d.apply) {
    case Apply::absolute: return draw;
    case Apply::relative: return nominal_value * (1.0 + draw);
    case Apply::offset: return nominal_value + draw;
  }
  return draw;
}

}  // namespace

Distribution make_distribution(const DispersionOptions& d) {
  if (d.distribution == "normal") return Distribution::normal(d.mean, d.std);
  if (d.distribution == "truncated_normal") return Distribution::truncated_normal(d.mean, d.std, d.lower, d.upper);
  if (d.distribution == "uniform") return Distribution::uniform(d.lower, d.upper);
  if (d.distribution == "lognormal") return Distribution::lognormal(d.mu, d.sigma);
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
  for (const auto& d : c.dispersions) {
    const int n = d.per == Per::run ? 1 : d.per == Per::bay ? L.n_bays_max : L.n_bays_max + 1;
    L.offset.push_back(L.total);
    L.count.push_back(n);
    L.total += n;
    L.distributions.push_back(make_distribution(d));
    const std::string e = L.distributions.back().validate();
    if (!e.empty()) throw std::invalid_argument("dispersion of " + d.key + ": " + e);
  }
  return L;
}

RunInputs calc_run_inputs(const CampaignOptions& c, const DimensionLayout& L, const double* u) {
  RunInputs in;
  in.scene = c.base;
  in.values.resize(c.dispersions.size());
  // Per-run draws first (the bay count among them), then the mast is built and dispersed.
  for (std::size_t i = 0; i < c.dispersions.size(); ++i) {
    const auto& d = c.dispersions[i];
    if (d.per != Per::run) continue;
    const double v = applied(d, find_nominal(c.base, d.key), L.distributions[i].calc_quantile(u[L.offset[i]]));
    in.values[i] = {v};
    set_run_key(in.scene, d.key, v);
  }
  in.mast = sim::build_mast(in.scene);
  const int n = in.mast.n_bays();
  for (std::size_t i = 0; i < c.dispersions.size(); ++i) {
    const auto& d = c.dispersions[i];
    if (d.per == Per::run) continue;
    auto& vals = in.values[i];
    vals.assign(static_cast<std::size_t>(L.count[i]), std::numeric_limits<double>::quiet_NaN());
    if (d.per == Per::bay) {
      for (int b = 1; b <= n; ++b) {
        double* f = bay_field(in.mast.bays[static_cast<std::size_t>(b - 1)], d.key);
        *f = applied(d, *f, L.distributions[i].calc_quantile(u[L.offset[i] + b - 1]));
        vals[static_cast<std::size_t>(b - 1)] = *f;
      }
    } else {
      for (int k = 0; k <= n; ++k) {
        double* f = frame_field(in.mast.frames[static_cast<std::size_t>(k)], d.key);
        *f = applied(d, *f, L.distributions[i].calc_quantile(u[L.offset[i] + k]));
        vals[static_cast<std::size_t>(k)] = *f;
      }
    }
  }
  // A dispersed strut mass or length keeps the slender-rod inertia unless J_c is set or dispersed.
  const bool inertia_given = c.base.mast.strut_inertia_kg_m2.has_value() ||
                             std::any_of(c.dispersions.begin(), c.dispersions.end(),
                                         [](const DispersionOptions& d) { return d.key == "mast.strut_inertia_kg_m2"; });
  if (!inertia_given)
    for (auto& b : in.mast.bays) b.strut_inertia_kg_m2 = b.strut_mass_kg * b.strut_length_m * b.strut_length_m / 12.0;
  return in;
}

}  // namespace truss::campaign
