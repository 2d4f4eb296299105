// Impacts of the free stack (docs/model.md §2, "free"): the laws of model/impacts.hpp for any
// number of moving frames. v: velocities of the moving frames lo..m in frame heights, M their
// tridiagonal mass matrix (model/frames.hpp; diag, sub), the driven frame m last (index N-1).
//
// Rail entry of bay m (plastic, through the rail impulse Lambda on the row
//   J = df/dy = (.., 0, J_l, J_m),  J_l = 1/2 + c D/(4x),  J_m = 1/2 - c D/(4x)  (docs/model.md §3, misprint 4),
// the impulse equations M dv = J Lambda [+ e_m P_d] with J (v + dv) = 0 after the impact):
//   torque / motor (finite drive force, no drive impulse):
//     z = M^-1 J,  Lambda = -(J v) / (J z),  dv = Lambda z;
//   velocity (the screw keeps u: dv_m = 0, the drive takes the impulse P_d):
//     z_J = M^-1 J, z_e = M^-1 e_m, [J z_J  J z_e; e_m z_J  e_m z_e] (Lambda, P_d) = (-J v, 0),
//     dv = Lambda z_J + P_d z_e.
//   Energy lost (1/2) dv' M dv (Carnot: J v+ = 0 and dv_m P_d = 0 make the constraint impulses
//   workless on the post-impact motion); drive impulse work P_d u.
// Impulsive start from rest in velocity mode (docs/model.md §2 "free": the momentum-consistent kick):
//   M dv = e_m P, dv_m = u  =>  P = u / (M^-1 e_m)_m, dv = P M^-1 e_m; a lossless ramp: the
//   drive's work (1/2) P u equals the kinetic energy (1/2) dv' M dv it leaves.
// The paper's literal start instead (the free frames at rest): dv = u e_m, the drive's impulse on
//   its row P = M_mm u and its work (1/2) P u = (1/2) M_mm u^2, the kinetic energy it leaves (the
//   stowed stack holds the other frames for the instant: no work).
// Contact landing (model/contacts.hpp), and any plastic impact with up to three constraint rows
// R_j (contact, rail, drive speed) that must change by d_j = R_j dv (a closing contact J v+ = 0,
// so d = -J v; the rail and the screw keep their velocity conditions, d = 0):
//   M dv = sum_j R_j Lambda_j,  z_j = M^-1 R_j,  S Lambda = d,  S_jk = R_j z_k;  dv = sum_j Lambda_j z_j.
// Each is one tridiagonal solve per row: O(N), no dense matrix (model/tridiagonal.hpp).
#pragma once
#include <vector>

#include <Eigen/Core>
#include <Eigen/LU>

#include "model/tridiagonal.hpp"

namespace truss::model {

struct StackImpact {
  bool ok = false;                 // false if M is not SPD or the constraint does not act
  Eigen::VectorXd dv;              // velocity jumps of frames lo..m (m/s)
  double rail_impulse_Ns = 0;      // Lambda (all three pins)
  double drive_impulse_Ns = 0;     // P_d (velocity drive; the start impulse for the kick)
  double energy_loss_J = 0;        // (1/2) dv' M dv
  double drive_work_J = 0;         // P_d u
};

// (1/2) a' M a for the tridiagonal M.
inline double calc_tridiagonal_energy_J(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const Eigen::VectorXd& a) {
  double e = 0.0;
  for (Eigen::Index k = 0; k < a.size(); ++k) {
    e += 0.5 * diag[k] * a[k] * a[k];
    if (k > 0) e += sub[k] * a[k] * a[k - 1];
  }
  return e;
}

// Rail entry; v.size() >= 2 (the lower frame m-1 moves, or is at rest with v = 0 but in the set).
inline StackImpact calc_stack_rail_entry(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const Eigen::VectorXd& v,
                                         double J_l, double J_m, bool drive_holds_speed, TridiagonalWork& w) {
  const Eigen::Index N = v.size();
  StackImpact r;
  Eigen::VectorXd J = Eigen::VectorXd::Zero(N), zJ;
  J[N - 2] = J_l;
  J[N - 1] = J_m;
  if (!solve_tridiagonal(diag, sub, J, zJ, w)) return r;
  const double Jv = J.dot(v), JzJ = J.dot(zJ);
  if (!drive_holds_speed) {
    if (!(JzJ > 0.0)) return r;
    r.rail_impulse_Ns = -Jv / JzJ;
    r.dv = r.rail_impulse_Ns * zJ;
  } else {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(N), ze;
    e[N - 1] = 1.0;
    if (!solve_tridiagonal(diag, sub, e, ze, w)) return r;
    const double a11 = JzJ, a12 = J.dot(ze), a22 = ze[N - 1], det = a11 * a22 - a12 * a12;
    if (!(det > 0.0)) return r;  // J and e_m parallel: the rail cannot act on the free frames
    r.rail_impulse_Ns = -Jv * a22 / det;
    r.drive_impulse_Ns = Jv * a12 / det;
    r.dv = r.rail_impulse_Ns * zJ + r.drive_impulse_Ns * ze;
    r.dv[N - 1] = 0.0;  // exactly: the screw keeps the driven frame's speed
  }
  r.energy_loss_J = calc_tridiagonal_energy_J(diag, sub, r.dv);
  r.drive_work_J = r.drive_impulse_Ns * v[N - 1];
  r.ok = true;
  return r;
}

// Velocity-mode start of frames lo..m from rest: the driven frame jumps to u.
inline StackImpact calc_stack_start_kick(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, double u, TridiagonalWork& w) {
  const Eigen::Index N = diag.size();
  StackImpact r;
  Eigen::VectorXd e = Eigen::VectorXd::Zero(N), ze;
  e[N - 1] = 1.0;
  if (!solve_tridiagonal(diag, sub, e, ze, w) || !(ze[N - 1] > 0.0)) return r;
  r.drive_impulse_Ns = u / ze[N - 1];
  r.dv = r.drive_impulse_Ns * ze;
  r.dv[N - 1] = u;
  r.drive_work_J = 0.5 * r.drive_impulse_Ns * u;
  r.ok = true;
  return r;
}

inline StackImpact calc_stack_start_rest(const Eigen::VectorXd& diag, double u) {
  const Eigen::Index N = diag.size();
  StackImpact r;
  if (!(diag[N - 1] > 0.0)) return r;
  r.dv = Eigen::VectorXd::Zero(N);
  r.dv[N - 1] = u;
  r.drive_impulse_Ns = diag[N - 1] * u;
  r.drive_work_J = 0.5 * r.drive_impulse_Ns * u;
  r.ok = true;
  return r;
}

// Plastic impact with the rows R_j and required changes d_j (1 <= rows <= 3). impulses: Lambda_j.
struct ConstrainedImpact {
  bool ok = false;
  Eigen::VectorXd dv;
  Eigen::Vector3d impulses = Eigen::Vector3d::Zero();
  double energy_loss_J = 0;  // (1/2) dv' M dv
};
inline ConstrainedImpact calc_constrained_impact(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub,
                                                 const std::vector<Eigen::VectorXd>& rows, const Eigen::Vector3d& d,
                                                 TridiagonalWork& w) {
  ConstrainedImpact r;
  const int k = static_cast<int>(rows.size());
  if (k < 1 || k > 3) return r;
  std::vector<Eigen::VectorXd> z(static_cast<std::size_t>(k));
  for (int j = 0; j < k; ++j)
    if (!solve_tridiagonal(diag, sub, rows[static_cast<std::size_t>(j)], z[static_cast<std::size_t>(j)], w)) return r;
  Eigen::MatrixXd S(k, k);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) S(i, j) = rows[static_cast<std::size_t>(i)].dot(z[static_cast<std::size_t>(j)]);
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(S);
  if (!lu.isInvertible()) return r;
  const Eigen::VectorXd L = lu.solve(d.head(k));
  r.dv = Eigen::VectorXd::Zero(diag.size());
  for (int j = 0; j < k; ++j) { r.dv += L[j] * z[static_cast<std::size_t>(j)]; r.impulses[j] = L[j]; }
  r.energy_loss_J = calc_tridiagonal_energy_J(diag, sub, r.dv);
  r.ok = r.dv.allFinite();
  return r;
}

}  // namespace truss::model
