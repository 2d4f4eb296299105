// Linear solves with the mast's mass matrix, which is symmetric tridiagonal (docs/model.md §3: bay i
// couples only frames i-1 and i), in O(n) and without a dense matrix:
//   solve_tridiagonal:  M x = r  (Thomas algorithm; M is symmetric positive definite, so no
//                                 pivoting is needed and the elimination is stable)
//   solve_bordered:     [M  a] [x     ]   [r]
//                       [a' 0] [lambda] = [s]   (one constraint row, paper eqs. 19-20)
//     with x = M^-1 r - lambda M^-1 a and a' x = s:
//     lambda = (a' M^-1 r - s) / (a' M^-1 a)  -- two tridiagonal solves and a scalar.
//   solve_tail_constrained:  M x = r + C mu,  C' x = s  (k <= 2 constraint columns C that are zero
//     but on the last two rows, the rail and drive rows of the free stack's phase B):
//     one forward elimination of r, the columns' elimination on their two rows only, the k x k
//     system C' M^-1 C mu = s - C' M^-1 r from the last two rows of the sweeps, and one back
//     substitution of r + C mu -- the cost of a single tridiagonal solve.
// diag[k] = M[k,k], sub[k] = M[k,k-1] (sub[0] unused), as model/frames.hpp assembles them.
// The sweeps carry the previous row's values in locals, not through the work vectors, so that the
// chain of dependent divisions does not also wait on a store and a load per row.
#pragma once
#include <Eigen/Core>

namespace truss::model {

// Work space of the solves (kept by the caller, so that the functions stay pure).
struct TridiagonalWork {
  Eigen::VectorXd c, d, y, z;
};

// Solves M x = r; x may alias r. Returns false if a pivot is not positive (M not SPD).
inline bool solve_tridiagonal(const Eigen::Ref<const Eigen::VectorXd>& diag, const Eigen::Ref<const Eigen::VectorXd>& sub,
                              const Eigen::Ref<const Eigen::VectorXd>& r, Eigen::VectorXd& x, TridiagonalWork& w) {
  const Eigen::Index n = diag.size();
  w.c.resize(n);
  w.d.resize(n);
  double piv = diag[0];
  if (!(piv > 0.0)) return false;
  double c = n > 1 ? sub[1] / piv : 0.0, d = r[0] / piv;
  w.c[0] = c;
  w.d[0] = d;
  for (Eigen::Index k = 1; k < n; ++k) {
    piv = diag[k] - sub[k] * c;
    if (!(piv > 0.0)) return false;
    c = k + 1 < n ? sub[k + 1] / piv : 0.0;
    d = (r[k] - sub[k] * d) / piv;
    w.c[k] = c;
    w.d[k] = d;
  }
  x.resize(n);
  double xk = d;
  x[n - 1] = xk;
  for (Eigen::Index k = n - 2; k >= 0; --k) x[k] = xk = w.d[k] - w.c[k] * xk;
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

// Solves M x = r + sum_j mu_j cols[j], cols[j]' x = s[j], j < k (k = 1 or 2), where every cols[j] is
// zero but on rows n-2, n-1 (the other rows are not read). Returns false if M is not SPD or the
// k x k system C' M^-1 C is singular.
inline bool solve_tail_constrained(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const Eigen::VectorXd& r,
                                   const Eigen::VectorXd* cols, int k, const double* s, Eigen::VectorXd& x, double* mu,
                                   TridiagonalWork& w) {
  const Eigen::Index n = diag.size();
  if (n < 2 || k < 1 || k > 2) return false;
  w.c.resize(n);
  w.d.resize(n);
  double piv = diag[0], piv_tail[2] = {0.0, 0.0};
  if (!(piv > 0.0)) return false;
  double c = sub[1] / piv, d = r[0] / piv;
  w.c[0] = c;
  w.d[0] = d;
  piv_tail[0] = piv;  // n == 2: row n-2 is row 0
  for (Eigen::Index i = 1; i < n; ++i) {
    piv = diag[i] - sub[i] * c;
    if (!(piv > 0.0)) return false;
    c = i + 1 < n ? sub[i + 1] / piv : 0.0;
    d = (r[i] - sub[i] * d) / piv;
    w.c[i] = c;
    w.d[i] = d;
    if (i >= n - 2) piv_tail[i - (n - 2)] = piv;
  }
  // Rows n-2, n-1 of the forward sweep (e) and of the solution (z) for r (index 2) and each column.
  const Eigen::Index a = n - 2, b = n - 1;
  double e0[3], e1[3], z0[3], z1[3];
  for (int j = 0; j < k; ++j) {
    e0[j] = cols[j][a] / piv_tail[0];
    e1[j] = (cols[j][b] - sub[b] * e0[j]) / piv_tail[1];
  }
  e0[2] = w.d[a];
  e1[2] = w.d[b];
  for (int j = 0; j < 3; ++j) {
    if (j >= k && j < 2) continue;
    z1[j] = e1[j];
    z0[j] = e0[j] - w.c[a] * z1[j];
  }
  const auto dot = [&](int i, int j) { return cols[i][a] * z0[j] + cols[i][b] * z1[j]; };
  if (k == 1) {
    const double S = dot(0, 0);
    if (!(S != 0.0)) return false;
    mu[0] = (s[0] - dot(0, 2)) / S;
  } else {
    const double S00 = dot(0, 0), S01 = dot(0, 1), S10 = dot(1, 0), S11 = dot(1, 1);
    const double det = S00 * S11 - S01 * S10, r0 = s[0] - dot(0, 2), r1 = s[1] - dot(1, 2);
    if (!(det != 0.0)) return false;
    mu[0] = (r0 * S11 - S01 * r1) / det;
    mu[1] = (S00 * r1 - S10 * r0) / det;
  }
  for (int j = 0; j < k; ++j) {
    w.d[a] += mu[j] * e0[j];
    w.d[b] += mu[j] * e1[j];
  }
  x.resize(n);
  double xi = w.d[b];
  x[b] = xi;
  for (Eigen::Index i = n - 2; i >= 0; --i) x[i] = xi = w.d[i] - w.c[i] * xi;
  return true;
}

}  // namespace truss::model
