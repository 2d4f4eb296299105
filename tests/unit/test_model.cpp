// Unit tests of src/model: each function alone, against independent transcriptions of the
// paper's equations (tests/test_helpers.hpp) and against Table 1 geometry (docs/model.md §2 and 4).
#include <catch2/catch.hpp>
#include <cmath>

#include "model/bay.hpp"
#include "model/frames.hpp"
#include "model/panels.hpp"
#include "model/rail.hpp"
#include "test_helpers.hpp"

using namespace truss::model;
using truss::testing::make_uneven_mast;
using truss::testing::paper_bay_T;
using truss::testing::paper_panel_T;

namespace {

// Total kinetic energy of moving frames lo..m (frames below lo at rest), from the paper's eq. 1
// and 2, with the locked part rigid (eq. 3).
double paper_T(const MastParams& mast, const ActiveFrames& a, const std::vector<double>& y, const std::vector<double>& v) {
  double T = 0;
  for (int i = std::max(a.lo, 1); i <= a.m; ++i)
    T += paper_bay_T(mast.bay(i), mast.frame(i).mass_kg, y[i], y[i - 1], v[i], v[i - 1]);
  if (a.lo == 0) T += 0.5 * mast.frame(0).mass_kg * v[0] * v[0];
  T += 0.5 * a.locked_mass_kg * v[a.m] * v[a.m];
  if (mast.panels.enabled()) T += paper_panel_T(mast.panels, y[a.m] + a.panel_height_offset_m, v[a.m]);
  return T;
}

// Potential of bays 1..top (the bays above are locked, their potential constant).
double paper_U(const MastParams& mast, const std::vector<double>& y, int top) {
  double U = 0;
  for (int i = 1; i <= top; ++i) {
    const double b2 = (mast.frame(i - 1).side_m * mast.frame(i - 1).side_m + mast.frame(i - 1).side_m * mast.frame(i).side_m +
                       mast.frame(i).side_m * mast.frame(i).side_m) / 3.0;
    const double L = std::sqrt(b2 + (y[i] - y[i - 1]) * (y[i] - y[i - 1]));
    const auto& b = mast.bay(i);
    if (L > b.diagonal_free_length_m) U += 3 * b.diagonal_stiffness_N_per_m * (L - b.diagonal_free_length_m) * (L - b.diagonal_free_length_m);
  }
  return U;
}

}  // namespace

TEST_CASE("mass matrix, velocity terms and spring forces match finite differences of the paper's energies", "[model]") {
  // J_c = 2.7 m_s l_s^2/12 (make_uneven_mast): misprint 1 of docs/model.md would show here.
  // Openings 0.05-0.22 m: every bay slack (taut from about 0.27 m); openings 0.30 m: bays 2 and 4
  // taut. With and without the bay table (its slack bound skips the square root of slack bays).
  for (int combo = 0; combo < 8; ++combo) {
    const bool panels = combo & 1, taut = combo & 2, table = combo & 4;
    MastParams mast = make_uneven_mast(6);
    if (panels) mast.panels = PanelParams{12, 0.9, 0.3, 0.36};
    const std::vector<BayConstants> bays = calc_bay_table(mast);
    ActiveFrames a;
    a.lo = 1; a.m = 4; a.locked_mass_kg = 2.2; a.panel_height_offset_m = 0.8;
    if (table) a.bays = bays.data();
    std::vector<double> y = taut ? std::vector<double>{0.0, 0.05, 0.35, 0.50, 0.80, 0.0, 0.0}
                                 : std::vector<double>{0.0, 0.05, 0.21, 0.40, 0.62, 0.0, 0.0};
    std::vector<double> v = {0.0, 0.03, -0.07, 0.11, 0.09, 0.0, 0.0};
    FrameSystem sys;
    calc_frame_system(mast, a, y.data(), v.data(), 0, sys);
    INFO("panels " << panels << " taut " << taut << " table " << table);
    if (taut) CHECK(sys.spring_forces[1] != 0.0);
    const int N = a.size();
    // M_jk = d2T / dv_j dv_k: T is quadratic in v, so a central difference is exact up to rounding.
    const double hv = 1e-3;
    for (int j = 0; j < N; ++j)
      for (int k = 0; k < N; ++k) {
        auto Tv = [&](double dj, double dk) {
          auto vv = v; vv[a.lo + j] += dj; vv[a.lo + k] += dk;
          return paper_T(mast, a, y, vv);
        };
        const double Mjk = (Tv(hv, hv) - Tv(hv, -hv) - Tv(-hv, hv) + Tv(-hv, -hv)) / (4 * hv * hv);
        double model = 0;
        if (j == k) model = sys.diag[j];
        else if (j == k + 1) model = sys.sub[j];
        else if (k == j + 1) model = sys.sub[k];
        INFO("panels " << panels << " M[" << j << "," << k << "]");
        CHECK(model == Approx(Mjk).margin(1e-8).epsilon(1e-8));
      }
    // r_k = dT/dy_k - sum_j d(dT/dv_k)/dy_j v_j (Lagrange: M y'' = r + Q). Central differences in
    // y with h = 1e-5 m: truncation ~ h^2 T''' ~ 1e-10 relative, so 1e-7 is safe.
    const double hy = 1e-5;
    auto dT_dvk = [&](const std::vector<double>& yy, int k) {
      auto vp = v, vm = v; vp[a.lo + k] += hv; vm[a.lo + k] -= hv;
      return (paper_T(mast, a, yy, vp) - paper_T(mast, a, yy, vm)) / (2 * hv);
    };
    for (int k = 0; k < N; ++k) {
      auto yp = y, ym = y; yp[a.lo + k] += hy; ym[a.lo + k] -= hy;
      double r = (paper_T(mast, a, yp, v) - paper_T(mast, a, ym, v)) / (2 * hy);
      for (int j = 0; j < N; ++j) {
        auto yjp = y, yjm = y; yjp[a.lo + j] += hy; yjm[a.lo + j] -= hy;
        r -= (dT_dvk(yjp, k) - dT_dvk(yjm, k)) / (2 * hy) * v[a.lo + j];
      }
      INFO("panels " << panels << " r[" << k << "]");
      CHECK(sys.velocity_terms[k] == Approx(r).margin(1e-9).epsilon(1e-6));
      const double Q = -(paper_U(mast, yp, a.m) - paper_U(mast, ym, a.m)) / (2 * hy);
      CHECK(sys.spring_forces[k] == Approx(Q).margin(1e-8).epsilon(1e-7));
    }
    // Kinetic energy: the model's (1/2) v^T M v equals the paper's T.
    CHECK(calc_kinetic_energy_J(sys, a, v.data()) == Approx(paper_T(mast, a, y, v)).epsilon(1e-13));
  }
}

TEST_CASE("frame 0 adds its own mass when it moves", "[model]") {
  MastParams mast = make_uneven_mast(2);
  ActiveFrames a; a.lo = 0; a.m = 1; a.locked_mass_kg = 1.0;
  std::vector<double> y = {0.1, 0.3, 0.0}, v = {0.02, 0.05, 0.0};
  FrameSystem sys;
  calc_frame_system(mast, a, y.data(), v.data(), 0, sys);
  CHECK(calc_kinetic_energy_J(sys, a, v.data()) == Approx(paper_T(mast, a, y, v)).epsilon(1e-13));
}

TEST_CASE("the hinge-coordinate strut energy g(x) equals G(D) (dD/dx)^2 and stays finite at the lock", "[model]") {
  const MastParams mast = make_uneven_mast(1);
  const BayParams& b = mast.bay(1);
  const double l = b.strut_length_m;
  // In frame heights G(D) loses digits as x -> 0 (4 l^2 - D^2 = 4 x^2 by cancellation): the
  // identity is checked where that form is still accurate, g itself everywhere.
  for (double x : {0.15, 0.08, 1e-2, 1e-3, 1e-6}) {
    const double s = std::sqrt(l * l - x * x), D = 2 * s, dDdx = -2 * x / s;
    if (x >= 1e-3) CHECK(calc_g_hinge(b, x) == Approx(calc_G(b, D) * dDdx * dDdx).epsilon(1e-9));
    CHECK(std::isfinite(calc_g_hinge(b, x)));
    const double h = 1e-7;
    CHECK(calc_dg_hinge_dx(b, x) == Approx((calc_g_hinge(b, x + h) - calc_g_hinge(b, x - h)) / (2 * h)).epsilon(1e-5).margin(1e-9));
  }
  // at x = 0: (3/4 m_s + 3 J_c / l_s^2), the latch energy factor of docs/model.md §2
  CHECK(calc_g_hinge(b, 0.0) == Approx(0.75 * b.strut_mass_kg + 3 * b.strut_inertia_kg_m2 / (l * l)).epsilon(1e-15));
  CHECK(calc_dg_hinge_dx(b, 0.0) == 0.0);
}

TEST_CASE("Table 1 rail geometry: entry and lock heights (docs/model.md §2)", "[model][table1]") {
  RailParams rail;  // Table 1 defaults
  const double l = 0.18;
  const HeldRailEntry e = calc_held_rail_entry(rail, l, 0.0);
  REQUIRE(e.reachable);
  CHECK(std::abs(e.upper_height_m - 0.327473474) < 1e-9);
  CHECK(std::abs(e.hinge_x_m - 0.0747682) < 1e-7);   // docs/model.md gives 7 digits
  CHECK(std::abs(e.hinge_y_m - 0.1637367) < 1e-7);
  CHECK(std::abs(calc_rail_function_m(rail, e.hinge_x_m, e.hinge_y_m)) < 1e-15);
  CHECK(std::abs(calc_lock_upper_height_m(rail, l) - 0.540049126) < 1e-9);
  CHECK(std::abs(calc_lock_lower_height_m(rail, l) - 0.180049126) < 1e-9);
  // the held hinge is outside the rail (f > 0) before entry, all along the quarter circle
  for (double th = 0; th < e.theta_rad; th += 0.01)
    CHECK(calc_rail_function_m(rail, l * std::cos(th), l * std::sin(th)) > 0.0);
}

TEST_CASE("rails that a held lower frame can never meet are detected", "[model]") {
  RailParams far;  far.y_m = 0.5;    // rail above the reach of the hinge: f(pi/2) > 0
  CHECK_FALSE(calc_held_rail_entry(far, 0.18, 0.0).reachable);
  RailParams low; low.x_m = -0.2; low.y_m = 0.3;  // hinge starts already past the rail: f(0) < 0
  CHECK_FALSE(calc_held_rail_entry(low, 0.18, 0.0).reachable);
}

TEST_CASE("on-rail kinematics: derivatives, rail function and inverse without cancellation", "[model]") {
  RailParams rail;
  const double l = 0.18;
  for (double x : {0.07, 0.03, 1e-4}) {
    const OnRailKinematics k = calc_on_rail(rail, l, x);
    const double h = 1e-6;
    const OnRailKinematics kp = calc_on_rail(rail, l, x + h), km = calc_on_rail(rail, l, x - h);
    CHECK(k.dY == Approx((kp.Y - km.Y) / (2 * h)).epsilon(1e-8));
    CHECK(k.dZ == Approx((kp.Z - km.Z) / (2 * h)).epsilon(1e-8));
    CHECK(k.d2Y == Approx((kp.dY - km.dY) / (2 * h)).epsilon(1e-6));
    CHECK(k.d2Z == Approx((kp.dZ - km.dZ) / (2 * h)).epsilon(1e-6));
    CHECK(std::abs(calc_rail_function_m(rail, x, 0.5 * (k.Y + k.Z))) < 1e-15);
    CHECK(k.Y - k.Z == Approx(2 * std::sqrt(l * l - x * x)).epsilon(1e-14));
  }
  // inverse: x from the remaining travel e to the lock, relative accuracy kept as x -> 0
  for (double x : {0.07, 1e-3, 1e-6, 1e-9}) {
    const double e = calc_lock_upper_height_m(rail, l) - calc_on_rail(rail, l, x).Y;  // ~ c x: exact enough
    const double x_back = calc_x_on_rail_from_travel(rail, l, e);
    CHECK(x_back == Approx(x).epsilon(x > 1e-7 ? 1e-9 : 1e-6));
  }
  CHECK(calc_x_on_rail_from_travel(rail, l, 0.0) == 0.0);
}

TEST_CASE("panel mass and slope (docs/model.md §3)", "[model]") {
  PanelParams p{8, 0.6, 0.25, 0.36};
  const double H = 2.1, h = 1e-6;
  // T = 1/2 M_p u^2 equals the independent transcription
  CHECK(0.5 * calc_panel_mass_kg(p, H) * 0.3 * 0.3 == Approx(paper_panel_T(p, H, 0.3)).epsilon(1e-14));
  CHECK(calc_half_panel_mass_slope_kg_per_m(p, H) ==
        Approx(0.5 * (calc_panel_mass_kg(p, H + h) - calc_panel_mass_kg(p, H - h)) / (2 * h)).epsilon(1e-7));
}

TEST_CASE("diagonals: tension only, tension and potential consistent", "[model]") {
  const MastParams mast = make_uneven_mast(1);
  const BayParams& b = mast.bay(1);
  const double b2 = calc_diagonal_offset_sq_m2(mast.frame(0), mast.frame(1));
  const double Dt = calc_taut_opening_m(b, b2);
  REQUIRE(Dt > 0);
  CHECK(calc_diagonal_tension_N(b, b2, 0.9 * Dt) == 0.0);
  CHECK(calc_bay_potential_J(b, b2, 0.9 * Dt) == 0.0);
  CHECK(calc_bay_dU_dD_N(b, b2, 0.9 * Dt) == 0.0);
  const double D = 1.1 * Dt, h = 1e-7;
  CHECK(calc_bay_dU_dD_N(b, b2, D) == Approx((calc_bay_potential_J(b, b2, D + h) - calc_bay_potential_J(b, b2, D - h)) / (2 * h)).epsilon(1e-6));
  // dU/dD = 6 T D / L: six diagonals, each pulling along its length
  CHECK(calc_bay_dU_dD_N(b, b2, D) == Approx(6 * calc_diagonal_tension_N(b, b2, D) * D / calc_diagonal_length_m(b2, D)).epsilon(1e-13));
  // equal frames: the offset is the frame side
  CHECK(calc_diagonal_offset_sq_m2({0.36, 0.5}, {0.36, 0.5}) == Approx(0.36 * 0.36).epsilon(1e-15));
}

// The slack bound (DiagonalConstants): at and below it the stretch sqrt(b^2 + D^2) - l_0, computed
// here as the paper writes it, is not positive, so the laws' zero without the square root is
// their exact value; and it lies within 1e-8 relative of the exact l_0^2 - b^2 (a bound far below
// it would leave the square root in most slack bays). Above the taut opening the laws with the
// bound are those without it, bit for bit.
TEST_CASE("diagonals: the slack bound gives the exact zero and is tight", "[model]") {
  const MastParams mast = make_uneven_mast(8);
  for (int i = 1; i <= mast.n_bays(); ++i) {
    const BayParams& b = mast.bay(i);
    const double b2 = calc_diagonal_offset_sq_m2(mast.frame(i - 1), mast.frame(i));
    const double l0 = b.diagonal_free_length_m, t = calc_slack_opening_sq_m2(b2, l0);
    INFO("bay " << i);
    REQUIRE(t > 0.0);
    CHECK(t <= l0 * l0 - b2);
    CHECK(t >= (l0 * l0 - b2) * (1.0 - 1e-8));
    // The largest D whose D * D is at the bound, and D = 0: the paper's stretch is not positive.
    double D = std::sqrt(t);
    while (D * D > t) D = std::nextafter(D, 0.0);
    while (std::nextafter(D, 1.0) * std::nextafter(D, 1.0) <= t) D = std::nextafter(D, 1.0);
    for (double d : {0.0, D, -D}) CHECK(std::sqrt(b2 + d * d) - l0 <= 0.0);
    const DiagonalConstants with = calc_bay_table(mast)[static_cast<std::size_t>(i)].diagonals;
    CHECK(with.slack_opening_sq_m2 == t);
    const double Dt = calc_taut_opening_m(b, b2);
    for (double d : {0.5 * Dt, D, Dt * (1.0 + 1e-6), 1.2 * Dt}) {
      CHECK(calc_bay_dU_dD_N(with, d) == calc_bay_dU_dD_N(b, b2, d));
      CHECK(calc_diagonal_tension_N(with, d) == calc_diagonal_tension_N(b, b2, d));
      CHECK(calc_bay_potential_J(with, d) == calc_bay_potential_J(b, b2, d));
    }
    CHECK(calc_diagonal_tension_N(with, Dt * (1.0 + 1e-6)) > 0.0);
  }
  // Taut at D = 0 (l_0 < b): no bound.
  CHECK(calc_slack_opening_sq_m2(0.36 * 0.36, 0.30) == -1.0);
}

// The frame system with the bays' constants kept (model::calc_bay_table) is the one computed from
// the parameters at each evaluation, bit for bit, whichever bays are slack or taut.
TEST_CASE("frame system: the same bits with and without the bay table", "[model]") {
  const MastParams mast = make_uneven_mast(12);
  const std::vector<BayConstants> bays = calc_bay_table(mast);
  for (int lo : {0, 1, 4}) {
    ActiveFrames a, t;
    a.lo = t.lo = lo; a.m = t.m = 11; a.locked_mass_kg = t.locked_mass_kg = 1.7;
    a.bay_m_in_hinge_coordinate = t.bay_m_in_hinge_coordinate = lo == 4;
    t.bays = bays.data();
    std::vector<double> y(13), v(13);
    for (int k = 0; k <= 12; ++k) {
      y[k] = k == 0 ? 0.0 : y[k - 1] + 0.32 * (0.5 + 0.5 * std::sin(1.3 * k));  // openings 0.01-0.32 m
      v[k] = k < lo ? 0.0 : 0.05 * std::cos(0.7 * k);
    }
    FrameSystem s0, s1;
    calc_frame_system(mast, a, y.data(), v.data(), 0, s0);
    calc_frame_system(mast, t, y.data(), v.data(), 0, s1);
    INFO("lo " << lo);
    for (int k = 0; k < a.size(); ++k) {
      CHECK(s1.diag[k] == s0.diag[k]);
      CHECK((k == 0 || s1.sub[k] == s0.sub[k]));
      CHECK(s1.velocity_terms[k] == s0.velocity_terms[k]);
      CHECK(s1.spring_forces[k] == s0.spring_forces[k]);
    }
  }
}

// The dip of a rail entry (model/rail.hpp): how deep below the rail line phase A continued
// through the entry goes, to second order. Checked against the hinge path itself: frames moving at
// constant accelerations from a state on the rail (f = 0, falling), f sampled every 1e-7 s until
// it rises again, its minimum times sin(beta) as the depth. The path's f is not a parabola (x_h
// is a square root of the heights), so the estimate errs by the third-order term, O(tau f''' / f'')
// relative, tau = -f'/f'' the time to the dip: about 1e-3 for these nearly grazing entries;
// a wrong x' or x'' would be off by order one.
TEST_CASE("rail entry dip: the dip of the continued hinge path, to second order", "[model][rail]") {
  const RailParams rail;
  const double l = 0.18, c = rail.cot_beta(), sb = std::sin(rail.beta_rad);
  auto f_of = [&](double ym, double ylo) {
    const double x = std::sqrt(l * l - 0.25 * (ym - ylo) * (ym - ylo));
    return calc_rail_function_m(rail, x, 0.5 * (ym + ylo));
  };
  struct Case { double D, u, w, au, aw; };
  // f' = -2e-3 .. -4e-3 m/s, f'' = 0.5 .. 1.6 m/s^2: dips of about 5e-6 m, 3 ms after the entry.
  for (const Case k : {Case{0.30, 0.1, 0.0585, 0.0, 0.4}, Case{0.25, 0.1, 0.0423, 0.0, 0.3},
                       Case{0.33, 0.05, 0.0346, 0.2, 0.6}}) {
    double ylo = 0.1, ym = ylo + k.D;
    const double f0 = f_of(ym, ylo);
    ym -= f0;  // both frames shifted: D kept, f = 0 (the entry)
    ylo -= f0;
    double fmin = 0.0, t = 0.0, f = 0.0;
    for (int i = 1; i < 20000000 && f <= fmin + 1e-15; ++i) {
      t = i * 1e-7;
      f = f_of(ym + k.u * t + 0.5 * k.au * t * t, ylo + k.w * t + 0.5 * k.aw * t * t);
      fmin = std::min(fmin, f);
    }
    const double m = calc_rail_entry_dip_m(rail, l, ym, ylo, k.u, k.w, k.au, k.aw);
    INFO("D " << k.D << ": dip " << -fmin * sb << " m, estimate " << m << " m, c " << c);
    REQUIRE(fmin < 0.0);
    CHECK(m == Approx(-fmin * sb).epsilon(5e-3));
  }
  // A grazing entry (f' = 0, f'' > 0) has no dip.
  CHECK(calc_rail_entry_dip_m(rail, l, 0.4, 0.1, 0.0, 0.0, 0.0, 0.3) == 0.0);
  // A pin still accelerating into the rail (f'' < 0): the dip over the horizon T = l / max(|u|, |f'|),
  // with f' and f'' by central differences of f along the path (step 1e-4 s: truncation 1e-8
  // relative, rounding 1e-16 / 1e-8 = 1e-8 relative in f'').
  const double ym = 0.4, ylo = 0.1, u = 0.1, au = 0.0, aw = -0.2, h = 1e-4;
  auto f_at = [&](double t) { return f_of(ym + u * t + 0.5 * au * t * t, ylo + 0.5 * aw * t * t); };
  const double fd = (f_at(h) - f_at(-h)) / (2 * h), fdd = (f_at(h) - 2 * f_at(0) + f_at(-h)) / (h * h);
  REQUIRE(fd < 0.0);
  REQUIRE(fdd < 0.0);
  const double T = l / std::max(u, -fd);
  CHECK(calc_rail_entry_dip_m(rail, l, ym, ylo, u, 0.0, au, aw) ==
        Approx(-(fd * T + 0.5 * fdd * T * T) * sb).epsilon(1e-6));
}

// The margin of an entry from its dip d and the slack s of the deploying bay's diagonals
// (docs/model-notes.md "Rail margin"), against what it must do: the dip alone while the diagonals
// are taut (s <= 0), so the margin still vanishes where a taut entry grazes; zero for a grazing
// entry whatever the slack (the margin is 0 exactly at the miss/entry boundary, and positive on
// every other entry); within min(d, s) of d + 0 and so continuous at d = s = 0; strictly
// increasing in the slack while d > 0, at the rate d^2 / (d + s)^2 (differentiated by hand),
// checked by central differences (step h = 1e-7 m: truncation O(h^2 / (d + s)^2) <= 1e-8 relative,
// rounding 4e-16 m / h absolute).
TEST_CASE("rail entry margin: the dip while taut, the slack in series with it while slack", "[model][rail]") {
  for (const double d : {0.0, 1e-9, 2e-3, 0.106}) {
    for (const double s : {-0.05, -1e-6, 0.0}) CHECK(calc_rail_entry_margin_m(d, s) == d);
    for (const double s : {1e-9, 3e-3, 0.012, 0.5}) {
      const double m = calc_rail_entry_margin_m(d, s);
      INFO("d " << d << " m, s " << s << " m: margin " << m << " m");
      if (d == 0.0) CHECK(m == 0.0);
      if (d == 0.0) continue;
      CHECK(m > d);
      CHECK(m - d <= std::min(d, s) * (1 + 1e-15));
      const double h = 1e-7, slope = (calc_rail_entry_margin_m(d, s + h) - calc_rail_entry_margin_m(d, s - h)) / (2 * h);
      CHECK(slope > 0.0);
      if (s > h) CHECK(slope == Approx(d * d / ((d + s) * (d + s))).epsilon(1e-6).margin(4e-16 * m / h));
    }
  }
  CHECK(calc_rail_entry_margin_m(1e-12, 1e-12) <= 2e-12);  // continuous at the corner d = s = 0
}
