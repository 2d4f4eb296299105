// Unilateral stack contacts of the free stack (docs/model.md §2 "free": optional contacts D_i >= 0,
// plastic). Frames in closed contact (D = 0) move as one rigid cluster; a cluster is a run of
// consecutive frames p..q, so with v_i = V_c for every frame i of cluster c the kinetic energy
// (1/2) v' M v of the tridiagonal M (model/frames.hpp) becomes (1/2) V' M_c V with
//   M_c[c,c]   = sum_{i in c} M[i,i] + 2 sum_{p < i <= q} M[i,i-1],
//   M_c[c,c-1] = M[p_c, p_c - 1]                 (only neighbouring clusters couple),
//   r_c        = sum_{i in c} r_i                (generalized force of the cluster),
// again tridiagonal: the clusters are solved in O(number of clusters) (model/tridiagonal.hpp).
// Contact force lambda_j >= 0 of a closed contact j (bay j: on frame j from frame j-1, upward),
// from the frame equations (M a)_i = F_i + lambda_i - lambda_{i+1} summed from the cluster's
// bottom p, whose own contact is open (lambda_p = 0):
//   lambda_j = sum_{i = p..j-1} (F_i - (M a)_i),   j = p+1..q.
// A frame resting on the canister's resting block (frames 0..k at rest on the floor, D = 0) feels
//   lambda_k = M[k,k+1] a_{k+1} - F_k,  F_k = G'(D) (dD/dt)^2 + dU/dD of bay k+1 (docs/model.md §3),
// the same force on every contact of the block (each frame of the block is at rest with D = 0 on
// both sides, where G'(0) = 0 and dU/dD(0) = 0). Landing (D_i falls to 0) is a plastic impact
// (model/free_impacts.hpp, calc_stack_impact); lift-off is lambda falling through 0.
#pragma once
#include <vector>

#include <Eigen/Core>

namespace truss::model {

// starts: first local frame of each cluster, ascending, starts[0] = 0; N frames in all.
inline void reduce_to_clusters(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub, const Eigen::VectorXd& rhs,
                               const std::vector<int>& starts, Eigen::VectorXd& diag_c, Eigen::VectorXd& sub_c,
                               Eigen::VectorXd& rhs_c) {
  const int C = static_cast<int>(starts.size()), N = static_cast<int>(diag.size());
  diag_c.setZero(C);
  sub_c.setZero(C);
  rhs_c.setZero(C);
  for (int c = 0; c < C; ++c) {
    const int p = starts[static_cast<std::size_t>(c)], q = c + 1 < C ? starts[static_cast<std::size_t>(c + 1)] - 1 : N - 1;
    for (int i = p; i <= q; ++i) {
      diag_c[c] += diag[i];
      rhs_c[c] += rhs[i];
      if (i > p) diag_c[c] += 2.0 * sub[i];
    }
    if (c > 0) sub_c[c] = sub[p];
  }
}

// Smallest contact force (N) of the closed contacts inside the clusters (frames whose local index
// is not a cluster start), with its local frame index in `at` (-1 and +inf if there is none).
// a: frame accelerations, F: frame forces (velocity terms + springs), both over the N frames.
inline double calc_min_cluster_contact_force_N(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub,
                                               const Eigen::VectorXd& F, const Eigen::VectorXd& a,
                                               const std::vector<int>& starts, int& at) {
  const int C = static_cast<int>(starts.size()), N = static_cast<int>(diag.size());
  double best = __builtin_inf();
  at = -1;
  for (int c = 0; c < C; ++c) {
    const int p = starts[static_cast<std::size_t>(c)], q = c + 1 < C ? starts[static_cast<std::size_t>(c + 1)] - 1 : N - 1;
    double lambda = 0.0;
    for (int i = p; i < q; ++i) {
      double Ma = diag[i] * a[i];
      if (i > 0) Ma += sub[i] * a[i - 1];
      if (i + 1 < N) Ma += sub[i + 1] * a[i + 1];
      lambda += F[i] - Ma;  // now lambda_{i+1}
      if (lambda < best) { best = lambda; at = i + 1; }
    }
  }
  return best;
}

}  // namespace truss::model
