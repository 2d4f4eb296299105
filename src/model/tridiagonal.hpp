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
//     substitution of r + C mu -- the cost of a single tridiagonal solve. From kTwistedRows rows
//     on, twisted (a "burn at both ends" factorization, Meurant, SIAM J. Matrix Anal. Appl. 13
//     (1992) 707): rows 0..p-1 eliminated downwards and rows n-1..p+1 upwards at the same time
//     (p = n/2), the two chains of dependent divisions side by side, joined at row p; the columns
//     C ride the upward sweep, their solution rows n-2, n-1 come from its substitution down from p.
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

// The k x k system S mu = s - C' y of solve_tail_constrained from rows a, b of y = M^-1 r (ya, yb)
// and of M^-1 cols[j] (za[j], zb[j]); false if S is singular.
inline bool solve_tail_multipliers(const Eigen::VectorXd* cols, int k, const double* s, Eigen::Index a, Eigen::Index b,
                                   double ya, double yb, const double* za, const double* zb, double* mu) {
  const auto dot = [&](int i, double zai, double zbi) { return cols[i][a] * zai + cols[i][b] * zbi; };
  if (k == 1) {
    const double S = dot(0, za[0], zb[0]);
    if (!(S != 0.0)) return false;
    mu[0] = (s[0] - dot(0, ya, yb)) / S;
    return true;
  }
  const double S00 = dot(0, za[0], zb[0]), S01 = dot(0, za[1], zb[1]), S10 = dot(1, za[0], zb[0]), S11 = dot(1, za[1], zb[1]);
  const double det = S00 * S11 - S01 * S10, r0 = s[0] - dot(0, ya, yb), r1 = s[1] - dot(1, ya, yb);
  if (!(det != 0.0)) return false;
  mu[0] = (r0 * S11 - S01 * r1) / det;
  mu[1] = (S00 * r1 - S10 * r0) / det;
  return true;
}

// From this many rows on, solve_tail_constrained runs twisted (the header).
inline constexpr Eigen::Index kTwistedRows = 8;

// solve_tail_constrained for n >= kTwistedRows, twisted at p = n/2 (the header). Work: c, d hold
// the downward sweep's ratios and right-hand side on rows < p and the upward sweep's on rows > p,
// then y = M^-1 r on rows >= p; y, z the upward sweeps of the columns, then their solutions.
inline bool solve_tail_twisted(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const Eigen::VectorXd& r,
                               const Eigen::VectorXd* cols, int k, const double* s, Eigen::VectorXd& x, double* mu,
                               TridiagonalWork& w) {
  const Eigen::Index n = diag.size(), p = n / 2, a = n - 2, b = n - 1;
  w.c.resize(n); w.d.resize(n); w.y.resize(n); w.z.resize(n);
  double piv = diag[0], q = diag[b];
  if (!(piv > 0.0) || !(q > 0.0)) return false;
  double c = sub[1] / piv, d = r[0] / piv;  // downward: x_i = d_i - c_i x_{i+1}
  double e = sub[b] / q, rq = 1.0 / q;      // upward: x_i = f_i - e_i x_{i-1}
  double f = r[b] * rq, g0 = cols[0][b] * rq, g1 = k > 1 ? cols[1][b] * rq : 0.0;
  w.c[0] = c; w.d[0] = d;
  w.c[b] = e; w.d[b] = f; w.y[b] = g0; w.z[b] = g1;
  for (Eigen::Index t = 1; t < p || b - t > p; ++t) {
    if (t < p) {
      piv = diag[t] - sub[t] * c;
      if (!(piv > 0.0)) return false;
      c = sub[t + 1] / piv;
      d = (r[t] - sub[t] * d) / piv;
      w.c[t] = c; w.d[t] = d;
    }
    const Eigen::Index i = b - t;
    if (i > p) {
      q = diag[i] - sub[i + 1] * e;
      if (!(q > 0.0)) return false;
      e = sub[i] / q;
      rq = 1.0 / q;
      f = (r[i] - sub[i + 1] * f) * rq;
      g0 = ((i == a ? cols[0][a] : 0.0) - sub[i + 1] * g0) * rq;
      g1 = k > 1 ? ((i == a ? cols[1][a] : 0.0) - sub[i + 1] * g1) * rq : 0.0;
      w.c[i] = e; w.d[i] = f; w.y[i] = g0; w.z[i] = g1;
    }
  }
  // Row p joins the sweeps; then rows p+1..n-1 of y and of the columns' solutions.
  const double gamma = diag[p] - sub[p] * c - sub[p + 1] * e;
  if (!(gamma > 0.0)) return false;
  double yv = (r[p] - sub[p] * d - sub[p + 1] * f) / gamma, z0 = -sub[p + 1] * g0 / gamma, z1 = -sub[p + 1] * g1 / gamma;
  w.d[p] = yv; w.y[p] = z0; w.z[p] = z1;
  for (Eigen::Index i = p + 1; i < n; ++i) {
    w.d[i] = yv = w.d[i] - w.c[i] * yv;
    w.y[i] = z0 = w.y[i] - w.c[i] * z0;
    w.z[i] = z1 = w.z[i] - w.c[i] * z1;
  }
  const double za[2] = {w.y[a], w.z[a]}, zb[2] = {w.y[b], w.z[b]};
  if (!solve_tail_multipliers(cols, k, s, a, b, w.d[a], w.d[b], za, zb, mu)) return false;
  const double mu1 = k > 1 ? mu[1] : 0.0;
  x.resize(n);
  for (Eigen::Index i = p; i < n; ++i) x[i] = w.d[i] + mu[0] * w.y[i] + mu1 * w.z[i];
  double xi = x[p];
  for (Eigen::Index i = p - 1; i >= 0; --i) x[i] = xi = w.d[i] - w.c[i] * xi;
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
  if (n >= kTwistedRows) return solve_tail_twisted(diag, sub, r, cols, k, s, x, mu, w);
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
