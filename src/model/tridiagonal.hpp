// Linear solves with the mast's mass matrix, which is symmetric tridiagonal (docs/model.md §3: bay i
// couples only frames i-1 and i), in O(n) and without a dense matrix:
//   solve_tridiagonal:  M x = r  (Thomas algorithm; M is symmetric positive definite, so no
//                                 pivoting is needed and the elimination is stable)
//   solve_bordered:     [M  a] [x     ]   [r]
//                       [a' 0] [lambda] = [s]   (one constraint row, paper eqs. 19-20)
//     with x = M^-1 r - lambda M^-1 a and a' x = s:
//     lambda = (a' M^-1 r - s) / (a' M^-1 a)  -- two tridiagonal solves and a scalar.
// diag[k] = M[k,k], sub[k] = M[k,k-1] (sub[0] unused), as model/frames.hpp assembles them.
#pragma once
#include <Eigen/Core>

namespace truss::model {

// Work space of the solves (kept by the caller, so that the functions stay pure).
struct TridiagonalWork {
  Eigen::VectorXd c, d, y, z;
};

// Solves M x = r; x may alias r. Returns false if a pivot is not positive (M not SPD).
inline bool solve_tridiagonal(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const Eigen::VectorXd& r,
                              Eigen::VectorXd& x, TridiagonalWork& w) {
  const Eigen::Index n = diag.size();
  w.c.resize(n);
  w.d.resize(n);
  double piv = diag[0];
  if (!(piv > 0.0)) return false;
  w.c[0] = n > 1 ? sub[1] / piv : 0.0;
  w.d[0] = r[0] / piv;
  for (Eigen::Index k = 1; k < n; ++k) {
    piv = diag[k] - sub[k] * w.c[k - 1];
    if (!(piv > 0.0)) return false;
    w.c[k] = k + 1 < n ? sub[k + 1] / piv : 0.0;
    w.d[k] = (r[k] - sub[k] * w.d[k - 1]) / piv;
  }
  x.resize(n);
  x[n - 1] = w.d[n - 1];
  for (Eigen::Index k = n - 2; k >= 0; --k) x[k] = w.d[k] - w.c[k] * x[k + 1];
  return true;
}

// Solves the bordered system above; returns false if M is not SPD or a' M^-1 a = 0 (the
// constraint does not act on the moving frames).
inline bool solve_bordered(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const Eigen::VectorXd& a,
                           const Eigen::VectorXd& r, double s, Eigen::VectorXd& x, double& lambda,
                           TridiagonalWork& w) {
  if (!solve_tridiagonal(diag, sub, r, w.y, w)) return false;
  if (!solve_tridiagonal(diag, sub, a, w.z, w)) return false;
  const double aza = a.dot(w.z);
  if (!(aza != 0.0)) return false;
  lambda = (a.dot(w.y) - s) / aza;
  x = w.y - lambda * w.z;
  return true;
}

}  // namespace truss::model
