// Solar-array blanket (paper eq. 2 corrected, docs/model.md §1 and 3).
//   H = y_m + sum_{locked} 2 l_s + h_tip,  P = n_p^2 l_p^2
//   M_p(H) = m_p/n_p^2 sum_{k=1..n_p} (k - 1/2)^2 + m_p H^2 / (4 n_p (P - H^2))
//            + n_p m_p l_p^2 / (12 (P - H^2))
//   T_p = (1/2) M_p(H) (dH/dt)^2, velocity term on the driven frame -(1/2) M_p'(H) (dH/dt)^2,
//   (1/2) M_p'(H) = m_p n_p l_p^2 H / (3 (P - H^2)^2)   (paper eq. 16 misprint: docs/model.md §2).
// Only called when PanelParams::enabled(): a scene without panels computes no panel terms.
#pragma once
#include "model/params.hpp"

namespace truss::model {

// Templates on the number type, as model/bay.hpp.
template <class T>
T calc_panel_mass_kg(const PanelParams& p, T H) {
  const double np = p.count;
  const double P = np * np * p.length_m * p.length_m;
  // sum_{k=1..n} (k - 1/2)^2 = n (4 n^2 - 1) / 12
  const double folded = p.mass_kg / (np * np) * np * (4.0 * np * np - 1.0) / 12.0;
  const T gap = P - H * H;
  return folded + p.mass_kg * H * H / (4.0 * np * gap) + np * p.mass_kg * p.length_m * p.length_m / (12.0 * gap);
}

template <class T>
T calc_half_panel_mass_slope_kg_per_m(const PanelParams& p, T H) {
  const double np = p.count;
  const double P = np * np * p.length_m * p.length_m;
  const T gap = P - H * H;
  return p.mass_kg * np * p.length_m * p.length_m * H / (3.0 * gap * gap);
}

}  // namespace truss::model
