// Equations of motion of the moving frames in frame heights (docs/model.md §3, paper eqs. 6-16
// corrected), written as M y'' = r + Q:
//   bay i adds 2G + 15/8 m_s + m_f,i to M[i,i], 2G + 15/8 m_s to M[i-1,i-1], -2G + 9/8 m_s to
//   M[i,i-1]; -G'(D) (dD/dt)^2 to r[i] and +G'(D) (dD/dt)^2 to r[i-1];
//   diagonals: -dU/dD on Q[i], +dU/dD on Q[i-1];
//   frame 0 moving: + m_f,0 on M[0,0];
//   driven frame m: + locked bays and tip (rigid, docs/model.md §1) + panel mass M_p(H) on M[m,m],
//   -(1/2) M_p'(H) (dH/dt)^2 on r[m].
// Frames below `lo` are held at rest (the held stack, or y_0 before the rail takes it). Bay m may
// be excluded from the G terms when the caller writes it in its hinge coordinate x (bay.hpp).
// Cost is linear in the number of moving frames; nothing else of the mast is touched.
#pragma once
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "model/bay.hpp"
#include "model/panels.hpp"
#include "model/params.hpp"

namespace truss::model {

// Bay i's constants of the system (model/bay.hpp): its laws' constants and its mass terms, the
// upper one with frame i's mass. The system is the same bits with them as without them.
struct BayConstants {
  StrutConstants strut;
  DiagonalConstants diagonals;
  double upper_mass_kg = 0;     // calc_regular_upper_mass_kg + m_f,i
  double lower_mass_kg = 0;     // calc_regular_lower_mass_kg
  double coupling_mass_kg = 0;  // calc_regular_coupling_mass_kg
};

// Bay i's constants with b^2 given; the diagonals' slack bound (DiagonalConstants) when asked.
inline BayConstants calc_bay_constants(const MastParams& mast, int i, double offset_sq_m2, bool slack_bound) {
  const BayParams& b = mast.bay(i);
  BayConstants c;
  c.strut = calc_strut_constants(b);
  c.diagonals = calc_diagonal_constants(b, offset_sq_m2);
  if (slack_bound) c.diagonals.slack_opening_sq_m2 = calc_slack_opening_sq_m2(offset_sq_m2, b.diagonal_free_length_m);
  c.upper_mass_kg = calc_regular_upper_mass_kg(b) + mast.frame(i).mass_kg;
  c.lower_mass_kg = calc_regular_lower_mass_kg(b);
  c.coupling_mass_kg = calc_regular_coupling_mass_kg(b);
  return c;
}

// Every bay's constants, indexed by the bay (entry 0 unused): for callers that evaluate the
// system many times on one mast (ActiveFrames::bays).
inline std::vector<BayConstants> calc_bay_table(const MastParams& mast) {
  std::vector<BayConstants> t(static_cast<std::size_t>(mast.n_bays() + 1));
  for (int i = 1; i <= mast.n_bays(); ++i)
    t[static_cast<std::size_t>(i)] =
        calc_bay_constants(mast, i, calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i)), true);
  return t;
}

struct ActiveFrames {
  int lo = 0;                          // lowest moving frame
  int m = 0;                           // driven frame (top of the moving part)
  bool bay_m_in_hinge_coordinate = false;  // omit bay m's G terms (caller adds g(x) dx/dt^2)
  double locked_mass_kg = 0;           // locked bays above m and the tip, rigid with frame m
  double panel_height_offset_m = 0;    // H = y_m + offset (used only if panels are enabled)
  // b^2 (calc_diagonal_offset_sq_m2) of bays m-1 and m when the caller computed them once for a
  // phase (its bays do not change); NaN: computed at each evaluation. The same value either way.
  std::array<double, 2> top_offset_sq_m2{std::numeric_limits<double>::quiet_NaN(),
                                         std::numeric_limits<double>::quiet_NaN()};
  // The bays' constants (calc_bay_table, indexed by the bay) when the caller keeps them for the
  // mast; nullptr: computed at each evaluation.
  const BayConstants* bays = nullptr;
  int size() const { return m - lo + 1; }
  double calc_offset_sq_m2(const MastParams& mast, int bay) const {
    const int k = bay - (m - 1);
    if (k >= 0 && !std::isnan(top_offset_sq_m2[static_cast<std::size_t>(k)]))
      return top_offset_sq_m2[static_cast<std::size_t>(k)];
    return calc_diagonal_offset_sq_m2(mast.frame(bay - 1), mast.frame(bay));
  }
};

struct FrameSystem {
  Eigen::VectorXd diag;            // M[k,k], k = frame - lo
  Eigen::VectorXd sub;             // M[k,k-1] (sub[0] unused)
  Eigen::VectorXd velocity_terms;  // r
  Eigen::VectorXd spring_forces;   // Q of the diagonals
  void resize(int n) {  // n frames; calc_frame_system writes every entry
    if (diag.size() != n) {
      diag.resize(n); sub.resize(n); velocity_terms.resize(n); spring_forces.resize(n);
    }
  }
  void clear(int n) {  // n frames, all zero
    resize(n);
    diag.setZero(); sub.setZero(); velocity_terms.setZero(); spring_forces.setZero();
  }
};

// The same system for at most three moving frames (the held stack's phases) in any number type
// T (double, or a dual number carrying a time derivative): no allocation.
template <class T>
struct SmallFrameSystem {
  std::array<T, 3> diag, sub, velocity_terms, spring_forces;
  void clear(int /*n*/) {  // all three (a fixed size: no call to memset)
    diag.fill(T(0.0)); sub.fill(T(0.0)); velocity_terms.fill(T(0.0)); spring_forces.fill(T(0.0));
  }
  void resize(int n) { clear(n); }  // the entries past n stay zero
};

// y, v: heights and velocities of frames first_frame.. (y[0] is frame first_frame); they must
// cover frames max(lo-1, 0)..m, and frames below lo must have v = 0. System: FrameSystem, or
// SmallFrameSystem<T> for up to three moving frames.
// Each entry is summed in registers, bay by bay from the bottom, in the order of the header's
// terms (bay i's upper frame, its lower frame, then its G terms) and stored once, when bay i + 1
// has added its share.
template <class T, class System>
void calc_frame_system(const MastParams& mast, const ActiveFrames& a, const T* y_in, const T* v_in, int first_frame,
                       System& out) {
  auto y = [&](int k) { return y_in[k - first_frame]; };
  auto v = [&](int k) { return v_in[k - first_frame]; };
  const int N = a.size();
  out.resize(N);
  const int first_bay = a.lo > 0 ? a.lo : 1;
  out.sub[0] = T(0.0);
  // The sums of the frame below bay i (frame i - 1), complete once bay i has added its share.
  T d_low(0.0), r_low(0.0), q_low(0.0);
  BayConstants own;
  for (int i = first_bay; i <= a.m; ++i) {
    if (!a.bays) own = calc_bay_constants(mast, i, a.calc_offset_sq_m2(mast, i), false);
    const BayConstants& c = a.bays ? a.bays[i] : own;
    const int k = i - a.lo;        // local index of the upper frame
    const bool lower_moves = (i - 1) >= a.lo;
    const T D = y(i) - y(i - 1);
    const T dD = v(i) - v(i - 1);
    const T dU = calc_bay_dU_dD_N(c.diagonals, D);
    T d_up(0.0), r_up(0.0), q_up(0.0), s(0.0);
    d_up += c.upper_mass_kg;
    q_up -= dU;
    if (lower_moves) {
      d_low += c.lower_mass_kg;
      s += c.coupling_mass_kg;
      q_low += dU;
    }
    if (!(i == a.m && a.bay_m_in_hinge_coordinate)) {
      const T G = calc_G(c.strut, D);
      const T vt = calc_dG_dD(c.strut, D) * dD * dD;
      d_up += 2.0 * G;
      r_up -= vt;
      if (lower_moves) {
        d_low += 2.0 * G;
        s -= 2.0 * G;
        r_low += vt;
      }
    }
    if (lower_moves) {
      out.diag[k - 1] = d_low;
      out.velocity_terms[k - 1] = r_low;
      out.spring_forces[k - 1] = q_low;
      out.sub[k] = s;
    }
    d_low = d_up; r_low = r_up; q_low = q_up;
  }
  const int top = N - 1;
  out.diag[top] = d_low;
  out.velocity_terms[top] = r_low;
  out.spring_forces[top] = q_low;
  if (a.lo == 0) out.diag[0] += mast.frame(0).mass_kg;
  out.diag[top] += a.locked_mass_kg;
  if (mast.panels.enabled()) {
    const T H = y(a.m) + a.panel_height_offset_m;
    const T u = v(a.m);
    out.diag[top] += calc_panel_mass_kg(mast.panels, H);
    out.velocity_terms[top] -= calc_half_panel_mass_slope_kg_per_m(mast.panels, H) * u * u;
  }
}

// Kinetic energy (1/2) v^T M v of the moving frames with the system above (J).
inline double calc_kinetic_energy_J(const FrameSystem& s, const ActiveFrames& a, const double* v) {
  double T = 0.0;
  for (int k = 0; k < a.size(); ++k) {
    const double vk = v[a.lo + k];
    T += 0.5 * s.diag[k] * vk * vk;
    if (k > 0) T += s.sub[k] * vk * v[a.lo + k - 1];
  }
  return T;
}

// Potential energy of all diagonals of the mast for frame heights y[0..n] (J).
inline double calc_potential_energy_J(const MastParams& mast, const double* y) {
  double U = 0.0;
  for (int i = 1; i <= mast.n_bays(); ++i) {
    const double b2 = calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
    U += calc_bay_potential_J(mast.bay(i), b2, y[i] - y[i - 1]);
  }
  return U;
}

}  // namespace truss::model
