// Shared test helpers: an independent transcription of the paper's energies (eq. 1, 2, 4 as
// corrected in docs/model.md), used to check the model's matrices by finite differences.
#pragma once
#include <cmath>
#include <vector>

#include "model/params.hpp"

namespace truss::testing {

// Kinetic energy of bay i straight from paper eq. 1 (note: no G, no simplification).
inline double paper_bay_T(const model::BayParams& b, double mf_upper, double yi, double yim1, double u, double w) {
  const double ms = b.strut_mass_kg, l = b.strut_length_m, Jc = b.strut_inertia_kg_m2;
  const double D = yi - yim1, den = 4 * l * l - D * D;
  return 3.0 / 32.0 * ms * (2.0 / den * D * D * (u - w) * (u - w) + (u + 3 * w) * (u + 3 * w) + (3 * u + w) * (3 * u + w)) +
         3.0 * Jc * (u - w) * (u - w) / den + 0.5 * mf_upper * u * u;
}

// Panel kinetic energy from docs/model.md §3 (eq. 2 corrected), dH/dt = u.
inline double paper_panel_T(const model::PanelParams& p, double H, double u) {
  const double np = p.count, P = np * np * p.length_m * p.length_m;
  double sum = 0;
  for (int k = 1; k <= p.count; ++k) sum += (k - 0.5) * (k - 0.5);
  const double Mp = p.mass_kg / (np * np) * sum + p.mass_kg * H * H / (4 * np * (P - H * H)) +
                    np * p.mass_kg * p.length_m * p.length_m / (12 * (P - H * H));
  return 0.5 * Mp * u * u;
}

// A mast whose bays and frames all differ (dispersed), with J_c != m_s l_s^2 / 12.
inline model::MastParams make_uneven_mast(int n, double spread = 0.05) {
  model::MastParams m;
  for (int i = 1; i <= n; ++i) {
    const double s = 1.0 + spread * std::sin(1.7 * i);
    model::BayParams b;
    b.strut_length_m = 0.18 * (1.0 + 0.01 * std::cos(2.3 * i));
    b.strut_mass_kg = 0.1 * s;
    b.strut_inertia_kg_m2 = 2.7 * b.strut_mass_kg * b.strut_length_m * b.strut_length_m / 12.0;  // not a slender rod
    b.diagonal_stiffness_N_per_m = 20.0 * (1.0 + spread * std::cos(0.9 * i));
    b.diagonal_free_length_m = 0.45 * (1.0 + 0.2 * spread * std::sin(0.4 * i));
    m.bays.push_back(b);
  }
  for (int k = 0; k <= n; ++k) m.frames.push_back({0.36 * (1.0 + 0.01 * std::sin(1.1 * k)), 0.5 * (1.0 + spread * std::cos(0.7 * k))});
  m.tip_mass_kg = 1.3;
  return m;
}

}  // namespace truss::testing
