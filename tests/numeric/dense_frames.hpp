// What the free-stack tests need to check the O(n) frame algebra (impacts, cluster reduction,
// contact forces, the DAE residual) against Eigen's dense solves, a second method: the tridiagonal
// M as a dense matrix, and one set-up of moving frames, so that every such check runs on the M
// that model/frames.hpp assembles.
#pragma once
#include <Eigen/Dense>

#include "model/frames.hpp"
#include "test_helpers.hpp"

namespace truss::testing {

// diag, sub as model/frames.hpp stores them (sub[0] unused).
inline Eigen::MatrixXd dense_tridiagonal(const Eigen::VectorXd& diag, const Eigen::VectorXd& sub) {
  const auto N = diag.size();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(N, N);
  for (Eigen::Index k = 0; k < N; ++k) {
    M(k, k) = diag[k];
    if (k > 0) M(k, k - 1) = M(k - 1, k) = sub[k];
  }
  return M;
}

// The frames 1..6 of an uneven mast moving, frame 0 held.
struct SixMovingFrames {
  model::MastParams mast = make_uneven_mast(6, 0.1);
  model::FrameSystem sys;
  // y, w: heights and velocities of frames 0..6.
  SixMovingFrames(const double (&y)[7], const double (&w)[7]) {
    model::ActiveFrames a;
    a.lo = 1;
    a.m = 6;
    a.locked_mass_kg = 1.3;
    model::calc_frame_system(mast, a, y, w, 0, sys);
  }
  Eigen::MatrixXd dense() const { return dense_tridiagonal(sys.diag, sys.sub); }
};

}  // namespace truss::testing
