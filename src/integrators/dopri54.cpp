#include "integrators/dopri54.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

namespace truss::integrators {

namespace {

// Butcher tableau of DOPRI5.
constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
constexpr double a21 = 1.0 / 5;
constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561, a54 = -212.0 / 729;
constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247, a64 = 49.0 / 176,
                 a65 = -5103.0 / 18656;
constexpr double a71 = 35.0 / 384, a73 = 500.0 / 1113, a74 = 125.0 / 192, a75 = -2187.0 / 6784,
                 a76 = 11.0 / 84;
constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920, e5 = -17253.0 / 339200,
                 e6 = 22.0 / 525, e7 = -1.0 / 40;
constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                 d4 = -10690763975.0 / 1880347072, d5 = 701980252875.0 / 199316789632,
                 d6 = -1453857185.0 / 822651844, d7 = 69997945.0 / 29380423;

// k[0..6] = k1..k7: k7 = f(t + h, y1) is FSAL, k6 the last stage at t + h.
constexpr RkPairTraits kTraits{.order = 5, .num_stages = 7, .fsal = 6, .last_stage = 5, .rhs_per_step = 6,
                               .stiff_boundary = 3.25, .pi_beta = 0.04, .ratio_min = 0.2, .ratio_max = 10.0};

class Dopri54Pair final : public RkPair {
 public:
  const RkPairTraits& traits() const override { return kTraits; }

  void resize(int n) override {
    for (auto& r : rc_) r.assign(n, 0.0);
  }

  // One Dormand-Prince step of size h from (t, y) into s.y1; returns the scaled RMS error
  // estimate (NaN if the state is not finite).
  double attempt_step(OdeSystem& sys, double t, double h, const double* y, RkStages& s,
                      const ErrorScale& scale) override {
    const int n = sys.size();
    auto& k1 = s.k[0]; auto& k2 = s.k[1]; auto& k3 = s.k[2]; auto& k4 = s.k[3];
    auto& k5 = s.k[4]; auto& k6 = s.k[5]; auto& k7 = s.k[6];
    auto& ytmp = s.ytmp; auto& ynew = s.y1;
    for (int i = 0; i < n; ++i) ytmp[i] = y[i] + h * a21 * k1[i];
    sys.calc_rhs(t + c2 * h, ytmp.data(), k2.data());
    for (int i = 0; i < n; ++i) ytmp[i] = y[i] + h * (a31 * k1[i] + a32 * k2[i]);
    sys.calc_rhs(t + c3 * h, ytmp.data(), k3.data());
    for (int i = 0; i < n; ++i) ytmp[i] = y[i] + h * (a41 * k1[i] + a42 * k2[i] + a43 * k3[i]);
    sys.calc_rhs(t + c4 * h, ytmp.data(), k4.data());
    for (int i = 0; i < n; ++i)
      ytmp[i] = y[i] + h * (a51 * k1[i] + a52 * k2[i] + a53 * k3[i] + a54 * k4[i]);
    sys.calc_rhs(t + c5 * h, ytmp.data(), k5.data());
    for (int i = 0; i < n; ++i)
      ytmp[i] = y[i] + h * (a61 * k1[i] + a62 * k2[i] + a63 * k3[i] + a64 * k4[i] + a65 * k5[i]);
    sys.calc_rhs(t + h, ytmp.data(), k6.data());
    for (int i = 0; i < n; ++i)
      ynew[i] = y[i] + h * (a71 * k1[i] + a73 * k3[i] + a74 * k4[i] + a75 * k5[i] + a76 * k6[i]);
    sys.calc_rhs(t + h, ynew.data(), k7.data());
    double err = 0.0;
    bool finite = true;
    for (int i = 0; i < n; ++i) {
      const double e = h * (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k7[i]);
      const double v = e / scale(y[i], ynew[i]);
      err += v * v;
      finite = finite && std::isfinite(ynew[i]);
    }
    err = std::sqrt(err / n);
    return finite ? err : std::numeric_limits<double>::quiet_NaN();
  }

  // Dense output coefficients of the accepted step on [t, t + h] (no right-hand side).
  long fill_dense(OdeSystem& sys, double, double h, const double* y, RkStages& s) override {
    const int n = sys.size();
    const auto& k1 = s.k[0]; const auto& k3 = s.k[2]; const auto& k4 = s.k[3];
    const auto& k5 = s.k[4]; const auto& k6 = s.k[5]; const auto& k7 = s.k[6];
    for (int i = 0; i < n; ++i) {
      const double ydiff = s.y1[i] - y[i];
      const double bspl = h * k1[i] - ydiff;
      rc_[0][i] = y[i];
      rc_[1][i] = ydiff;
      rc_[2][i] = bspl;
      rc_[3][i] = ydiff - h * k7[i] - bspl;
      rc_[4][i] = h * (d1 * k1[i] + d3 * k3[i] + d4 * k4[i] + d5 * k5[i] + d6 * k6[i] + d7 * k7[i]);
    }
    return 0;
  }

  void calc_dense(double th, double* y) const override {
    const double th1 = 1.0 - th;
    const std::size_t n = rc_[0].size();
    for (std::size_t i = 0; i < n; ++i)
      y[i] = rc_[0][i] + th * (rc_[1][i] + th1 * (rc_[2][i] + th * (rc_[3][i] + th1 * rc_[4][i])));
  }

 private:
  std::vector<double> rc_[5];  // dense output coefficients
};

}  // namespace

std::unique_ptr<RkPair> make_dopri54_pair() { return std::make_unique<Dopri54Pair>(); }

}  // namespace truss::integrators
