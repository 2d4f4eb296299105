#include "integrators/dop853.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "integrators/dop853_tableau.hpp"

namespace truss::integrators {

namespace {

using namespace dop853;

// k[0..15]: k[12] = f(t + h, y1) is FSAL, k[11] the last stage at t + h, k[13..15] the dense output's.
constexpr RkPairTraits kTraits{.order = 8, .num_stages = kStagesDense, .fsal = kStages, .last_stage = kStages - 1,
                               .rhs_per_step = kStages, .stiff_boundary = 6.1, .pi_beta = 0.0, .ratio_min = 0.333,
                               .ratio_max = 6.0};

class Dop853Pair final : public RkPair {
 public:
  const RkPairTraits& traits() const override { return kTraits; }

  void resize(int n) override {
    for (auto& r : rc_) r.assign(n, 0.0);
    ystart_.assign(n, 0.0);
    ydense_.assign(n, 0.0);
  }

  // One step of size h from (t, y) into s.y1, s.k[12] = f(t + h, s.y1); returns the scaled error
  // estimate of dop853.f (NaN if the state is not finite).
  double attempt_step(OdeSystem& sys, double t, double h, const double* y, RkStages& s,
                      const ErrorScale& scale) override {
    const int n = sys.size();
    auto& k = s.k;
    for (int st = 1; st < kStages; ++st) {
      for (int i = 0; i < n; ++i) s.ytmp[i] = y[i];
      for (int j = 0; j < st; ++j) {
        const double a = h * kA[st][j];
        if (a == 0.0) continue;
        const double* kj = k[j].data();
        for (int i = 0; i < n; ++i) s.ytmp[i] += a * kj[i];
      }
      sys.calc_rhs(t + kC[st] * h, s.ytmp.data(), k[st].data());
    }
    for (int i = 0; i < n; ++i) s.y1[i] = y[i];
    for (int j = 0; j < kStages; ++j) {
      const double b = h * kB[j];
      if (b == 0.0) continue;
      const double* kj = k[j].data();
      for (int i = 0; i < n; ++i) s.y1[i] += b * kj[i];
    }
    sys.calc_rhs(t + h, s.y1.data(), k[kStages].data());
    double e5 = 0.0, e3 = 0.0;
    bool finite = true;
    for (int i = 0; i < n; ++i) {
      double a5 = 0.0, a3 = 0.0;
      for (int j = 0; j < kStages; ++j) {
        a5 += kE5[j] * k[j][i];
        a3 += kE3[j] * k[j][i];
      }
      const double sc = scale(y[i], s.y1[i]);
      e5 += (a5 / sc) * (a5 / sc);
      e3 += (a3 / sc) * (a3 / sc);
      finite = finite && std::isfinite(s.y1[i]);
    }
    double den = e5 + 0.01 * e3;
    if (!(den > 0.0)) den = 1.0;
    const double err = std::abs(h) * e5 / std::sqrt(n * den);
    return finite && std::isfinite(err) ? err : std::numeric_limits<double>::quiet_NaN();
  }

  // The three dense-output stages, then the coefficients r0..r6 (dop853_tableau.hpp).
  long fill_dense(OdeSystem& sys, double t, double h, const double* y, RkStages& s) override {
    const int n = sys.size();
    auto& k = s.k;
    for (int st = kStages + 1; st < kStagesDense; ++st) {
      for (int i = 0; i < n; ++i) ydense_[i] = y[i];
      for (int j = 0; j < st; ++j) {
        const double a = h * kA[st][j];
        if (a == 0.0) continue;
        const double* kj = k[j].data();
        for (int i = 0; i < n; ++i) ydense_[i] += a * kj[i];
      }
      sys.calc_rhs(t + kC[st] * h, ydense_.data(), k[st].data());
    }
    for (int i = 0; i < n; ++i) {
      const double dy = s.y1[i] - y[i];
      rc_[0][i] = dy;
      rc_[1][i] = h * k[0][i] - dy;
      rc_[2][i] = 2.0 * dy - h * (k[0][i] + k[kStages][i]);
      for (int r = 0; r < 4; ++r) {
        double d = 0.0;
        for (int j = 0; j < kStagesDense; ++j) d += kD[r][j] * k[j][i];
        rc_[3 + r][i] = h * d;
      }
      ystart_[i] = y[i];
    }
    return kStagesDense - kStages - 1;
  }

  void calc_dense(double th, double* out) const override {
    const double u = 1.0 - th;
    const auto& r = rc_;
    const std::size_t n = ystart_.size();
    for (std::size_t i = 0; i < n; ++i)
      out[i] = ystart_[i] + th * (r[0][i] + u * (r[1][i] + th * (r[2][i] + u * (r[3][i] + th * (r[4][i] + u * (r[5][i] + th * r[6][i]))))));
  }

 private:
  std::vector<double> rc_[7], ystart_, ydense_;  // dense output: coefficients, the step's start, its stages' states
};

}  // namespace

std::unique_ptr<RkPair> make_dop853_pair() { return std::make_unique<Dop853Pair>(); }

}  // namespace truss::integrators
