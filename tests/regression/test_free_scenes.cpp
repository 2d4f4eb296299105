// The shipped free-stack scenes (campaigns/scenes/paper_free*.toml; docs/model.md §2 "free"):
// Table 1's free stack misses the rail (its diagonals, taut from D = 0.27 m, pull the free lower
// frame up), the slack one deploys with a small drive force before rail entry and a larger one
// after. The closest approach is checked against the time history (an independent sampling of
// the hinge path, distances computed here from the rail line).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "io/scene_toml.hpp"
#include "sim/simulate.hpp"

using namespace truss;

namespace {
sim::SceneOptions load(const char* name, const std::vector<std::string>& sets = {}) {
  return io::parse_scene_file(std::string(TRUSS_SOURCE_DIR) + "/campaigns/scenes/" + name, sets);
}
}  // namespace

TEST_CASE("paper_free.toml: the Table-1 free stack (contacts on) ends in rail miss with a closest approach above zero",
          "[regression][free]") {
  const sim::RunResult r = sim::simulate(load("paper_free.toml", {"run.output_step_s=0.001"}));
  REQUIRE(r.status == sim::RunStatus::rail_miss);
  CHECK(r.bays_completed == 0);
  CHECK(r.rail_miss_bay == 30);
  CHECK(r.rail_miss_closest_approach_m > 0.0);
  CHECK(r.rail_miss_closest_approach_time_s > 0.0);
  CHECK(r.rail_miss_closest_approach_time_s < r.rail_miss_above_rail_top_time_s);
  CHECK(r.rail_miss_above_rail_top_time_s < r.end_time_s);
  CHECK(r.message.find("closest approach") != std::string::npos);
  // Stop rule: the driven frame at the lock height plus one bay, y_r + 3 l_s, at speed 0.1 m/s.
  const double beta = 20.85 * M_PI / 180.0, yr = 0.15 + 0.08 / std::tan(beta), l = 0.18;
  CHECK(r.end_time_s == Approx((yr + 3 * l) / 0.1).epsilon(1e-9));
  // Distance of the hinge from the rail line through (x_l, y_l) at beta to the axis, sampled every
  // 1 ms: the refined minimum lies at or below every sample, and within the sampling error of
  // the best one (hinge speed ~0.05 m/s: a quadratic minimum moves by < 1e-6 m over 0.5 ms).
  const auto& h = r.history;
  REQUIRE(h.size() > 1000);
  double best = 1e9, t_best = 0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    const double d = (h.hinge_x_m[i] - 0.08) * std::cos(beta) + (h.hinge_y_m[i] - 0.15) * std::sin(beta);
    if (d < best) { best = d; t_best = h.t_s[i]; }
  }
  CHECK(r.rail_miss_closest_approach_m <= best + 1e-12);
  CHECK(r.rail_miss_closest_approach_m > best - 1e-6);
  CHECK(r.rail_miss_closest_approach_time_s == Approx(t_best).margin(2e-3));
  // Contacts on (the scene's): no frame passes through another (the landing event fires 1e-9 l_s
  // into a contact); lower frames lift off the stack (the rail miss is not an artefact of overlap).
  CHECK(r.min_bay_opening_m >= -2e-9 * l);
  CHECK(r.contact_lift_offs >= 1);
  // Contacts off (the paper's literal model): frames pass through each other (openings below
  // zero). The reported smallest opening lies at or below every sampled one of the deploying bay.
  const sim::RunResult off = sim::simulate(load("paper_free.toml", {"run.output_step_s=0.001", "stack.contacts=false"}));
  CHECK(off.status == sim::RunStatus::rail_miss);
  CHECK(off.rail_miss_closest_approach_m > 0.0);
  double d_min = 1e9;
  for (std::size_t i = 0; i < off.history.size(); ++i) d_min = std::min(d_min, off.history.y_driven_m[i] - off.history.y_lower_m[i]);
  CHECK(off.min_bay_opening_m < 0.0);
  CHECK(off.min_bay_opening_m <= d_min + 1e-12);
  CHECK(off.contact_lift_offs == 0);
  sim::SceneOptions held = load("table1.toml");
  CHECK(std::isnan(sim::simulate(held).min_bay_opening_m));  // not tracked for the held stack
}

TEST_CASE("paper_free_slack.toml: the free stack deploys; drive force small before entry, larger after",
          "[regression][free]") {
  const sim::RunResult r = sim::simulate(load("paper_free_slack.toml", {"run.output_step_s=0.001"}));
  REQUIRE(r.status == sim::RunStatus::ok);
  REQUIRE(r.bays_completed == 30);
  CHECK(std::abs(r.energy_residual_J) < 1e-6 * r.drive_work_J);  // rtol 1e-8 of the scene
  // Bay 30's stage: smooth drive force before its rail entry and between entry and lock.
  const sim::BayResult& b = r.bays[29];
  const auto& h = r.history;
  double before = 0, after = 0;
  for (std::size_t i = 0; i < h.size(); ++i) {
    if (h.bay[i] != 30 || h.t_s[i] <= 0.0) continue;
    (h.t_s[i] < b.entry_time_s ? before : after) =
        std::max(h.t_s[i] < b.entry_time_s ? before : after, std::abs(h.drive_force_N[i]));
  }
  INFO("max |F| before entry " << before << " N, after " << after << " N");
  CHECK(after > 3.0 * before);
}

TEST_CASE("free stack: a grazing approach that dips into the rail within a step enters it", "[regression][free]") {
  // l_0 = 0.47037997 m (a draw of campaigns/free_rail_miss.toml): the hinge of bay 13 dips about
  // 2e-5 m past the rail line and back between two step ends. Without the minimum-of-f event the
  // run ended in "rail miss" with a negative closest approach; the pin must enter the rail there.
  const sim::RunResult r = sim::simulate(load("paper_free.toml", {"mast.diagonal_free_length_m=0.47037996930478726", "stack.contacts=false"}));
  INFO(r.message);
  CHECK(r.bays_completed > 17);
  if (r.status == sim::RunStatus::rail_miss) CHECK(r.rail_miss_closest_approach_m > 0.0);
}

TEST_CASE("free_singular.toml: bay 1 straightens below the deploying bay 2 (singular configuration)",
          "[regression][free]") {
  // Frame 0 rests on the floor and bay 1 (frames 0, 1) is not deploying; the run must stop where
  // its hinge offset x_1 = sqrt(l^2 - D_1^2 / 4), computed here from the history's last row, is
  // 1e-4 l_s, inside the stage of bay 2 and before its pin meets the rail (bay 2 never entered).
  const double l = 0.18;
  for (const char* mode : {"velocity", "motor"}) {
    for (const char* integ : {"dopri54", "ida"}) {
      INFO(mode << ", " << integ);
      const sim::RunResult r = sim::simulate(load("free_singular.toml", {std::string("drive.mode=\"") + mode + "\"",
                                                                          std::string("run.integrator=\"") + integ + "\""}));
      REQUIRE(r.status == sim::RunStatus::singular_configuration);
      CHECK(r.message.find("bay 1 (not deploying)") != std::string::npos);
      CHECK(r.message.find("in the stage of bay 2") != std::string::npos);
      CHECK(r.bays_completed == 0);
      CHECK(std::isnan(r.bays[1].entry_time_s));
      const auto& h = r.history;
      REQUIRE(h.n_frames == 3);
      CHECK(h.t_s.back() == r.end_time_s);
      const double* last = h.frame_height_m.data() + (h.size() - 1) * 3;
      const double D1 = last[1] - last[0];
      CHECK(std::sqrt(std::max(0.0, l * l - 0.25 * D1 * D1)) < 1.01e-4 * l);
      CHECK(std::sqrt(std::max(0.0, l * l - 0.25 * D1 * D1)) > 0.9e-4 * l);  // not past it either
      CHECK(last[0] == 0.0);  // frame 0 still on the floor
    }
  }
}

TEST_CASE("one rail geometry for both stack modes: the free stack refuses what the held stack refuses",
          "[regression][free][rail]") {
  // The free stack holds frame 0 on the floor until bay 1's rail takes it and starts stowed, as the
  // held stack does, so a geometry the held stack refuses (docs/model-notes.md, "Rail geometry")
  // cannot deploy with free frames either. Reference: the held stack's refusal of the same scene.
  struct Case { const char* what; int n; double x_m, y_m, beta_deg, l0; };
  const std::vector<Case> cases = {
      {"2 bays, rail.y_m 0.24", 2, 0.08, 0.24, 20.85, 0.45},
      {"2 bays, rail.y_m 0.25", 2, 0.08, 0.25, 20.85, 0.45},
      {"2 bays, rail.y_m 0.24, l_0 0.42", 2, 0.08, 0.24, 20.85, 0.42},
      {"3 bays, a high rail at 15 deg", 3, 0.08, 0.25, 15.0, 0.49},
      {"the straight-bay limit", 1, 0.0114, 0.15, 20.85, 0.45},
      {"the stowed pin not clear", 1, 0.13, 0.15, 20.85, 0.45},
      {"rail.beta_deg 50", 1, 0.08, 0.15, 50.0, 0.45},
  };
  for (const Case& c : cases) {
    for (const auto dir : {model::Direction::deploy, model::Direction::retract}) {
      INFO(c.what << (dir == model::Direction::deploy ? ", deploy" : ", retract"));
      sim::SceneOptions s = load("table1.toml", {"run.output_step_s=0"});
      s.mast.n_bays = c.n;
      s.rail.x_m = c.x_m;
      s.rail.y_m = c.y_m;
      s.rail.beta_deg = c.beta_deg;
      s.mast.diagonal_free_length_m = c.l0;
      s.run.direction = dir;
      const sim::RunResult held = sim::simulate(s);
      REQUIRE(held.status == sim::RunStatus::invalid_input);
      CHECK(held.message.rfind("rail geometry: ", 0) == 0);
      s.stack.mode = sim::StackMode::free;
      for (const auto contacts : {sim::StackContacts::on, sim::StackContacts::off}) {
        s.stack.contacts = contacts;
        const sim::RunResult fr = sim::simulate(s);
        CHECK(fr.status == sim::RunStatus::invalid_input);
        CHECK(fr.message == held.message);
      }
    }
  }
  // The first case in closed form (independent of model/rail.hpp): the lock of bay 2 leaves frame 1
  // at y_r - l, and with frame 0 on the floor bay 1's pin, on the arc (l cos th, l sin th), meets
  // the rail y = y_r - c x where l (sin th + c cos th) = y_r, i.e. with the driven frame at
  // 2 l sin th_e, th_e = pi - atan(c) - asin(y_r / (l sqrt(1 + c^2))): below y_r - l here.
  const double l = 0.18, c = 1.0 / std::tan(20.85 * M_PI / 180.0), y_r = 0.24 + 0.08 * c;
  const double th = M_PI - std::atan(c) - std::asin(y_r / (l * std::sqrt(1.0 + c * c)));
  CHECK(2.0 * l * std::sin(th) < y_r - l);
}

TEST_CASE("a rail miss never reports a positive rail margin", "[regression][free][rail]") {
  // Without stack contacts the frames below can pass through each other and the floor: with a
  // higher rail (rail.y_m 0.22 m, a geometry the held stack runs) and l_0 = 0.5 m, bay 2's hinge is
  // already past the rail line when bay 3 locks, so it never crosses the line falling (no entry)
  // and its closest approach is negative. The margin is minus the approach's magnitude
  // (docs/model-notes.md, "Rail margin"): negative on every miss, as on an ordinary one (rail.y_m
  // 0.20 m, 4 bays, l_0 0.44 m). The hinge's side of the rail line at the stage start is computed
  // here from the history's frame heights (f = y_h - y_l + c (x_h - x_l)).
  const double l = 0.18, c = 1.0 / std::tan(20.85 * M_PI / 180.0);
  struct Case { double y_m; int n; double l0; };
  for (const Case k : {Case{0.20, 4, 0.44}, Case{0.22, 3, 0.5}}) {
    INFO("rail.y_m = " << k.y_m << ", " << k.n << " bays, l_0 = " << k.l0);
    sim::SceneOptions s = load("table1.toml", {"stack.mode=\"free\"", "run.output_step_s=0.001"});
    s.rail.y_m = k.y_m;
    s.mast.n_bays = k.n;
    s.mast.diagonal_free_length_m = k.l0;
    const sim::RunResult r = sim::simulate(s);
    REQUIRE(r.status == sim::RunStatus::rail_miss);
    CHECK(r.rail_margin_m < 0.0);
    CHECK(r.rail_margin_m == -std::abs(r.rail_miss_closest_approach_m));
    if (k.n != 3) continue;
    REQUIRE(r.rail_miss_bay == 2);
    CHECK(r.rail_miss_closest_approach_m < 0.0);
    const auto& h = r.history;
    std::size_t row = 0;
    while (row < h.size() && h.t_s[row] <= r.bays[2].lock_time_s) ++row;
    REQUIRE(row < h.size());
    const double* y = h.frame_height_m.data() + row * 4;
    const double D = y[2] - y[1], x = std::sqrt(l * l - 0.25 * D * D);
    CHECK(0.5 * (y[2] + y[1]) - k.y_m + c * (x - 0.08) < 0.0);
  }
}

TEST_CASE("paper_free.toml retracts with stack contacts in every drive mode", "[regression][free][retract]") {
  // The reverse of the rail miss scene: from the deployed mast the rail pushes each lower frame
  // back onto the stack; frames bounce on it (landings, lift-offs) but never pass through it.
  for (const char* mode : {"velocity", "torque", "motor"}) {
    INFO(mode);
    const sim::RunResult r = sim::simulate(load("paper_free.toml", {"run.direction=\"retract\"", std::string("drive.mode=\"") + mode + "\""}));
    INFO(r.message);
    REQUIRE(r.status == sim::RunStatus::ok);
    CHECK(r.bays_completed == 30);
    CHECK(r.contact_landings > 30);  // at least every rail exit onto the stack
    CHECK(r.min_bay_opening_m > -2e-9 * 0.18);
    CHECK(std::abs(r.energy_residual_J) < 1e-5 * (std::abs(r.drive_work_J) + r.energy_lost_J));  // rtol 1e-8 of the scene
  }
}

// The rail margin (docs/model-notes.md "Rail margin") is continuous through the boundary between a
// miss and an entry: the diagonal free length l_0 bisected to 2e-7 m between a miss (0.4700 m) and
// an entry (0.4710 m). Near the boundary the margin moves about 1.05 m per m of l_0 on either side
// (measured at l_0 = 0.4704 / 0.47042 and 0.47045 / 0.47048), so both sides of the last bracket
// lie within 3 brackets' worth of zero; a jump (e.g. an entry margin that does not go to zero as
// the entry grazes) would leave one side a finite distance away.
TEST_CASE("rail_margin_m: negative on a miss, positive on an entry, continuous through the boundary",
          "[regression][free]") {
  auto run = [](double l0) {
    return sim::simulate(load("paper_free.toml", {"stack.contacts=false", "run.output_step_s=0",
                                                  "mast.diagonal_free_length_m=" + fmt::format("{}", l0)}));
  };
  double miss = 0.4700, entry = 0.4710;
  sim::RunResult rm = run(miss), re = run(entry);
  REQUIRE(rm.status == sim::RunStatus::rail_miss);
  REQUIRE(re.status == sim::RunStatus::ok);
  CHECK(rm.rail_margin_m == -rm.rail_miss_closest_approach_m);
  while (entry - miss > 2e-7) {
    const double mid = 0.5 * (miss + entry);
    sim::RunResult r = run(mid);
    REQUIRE((r.status == sim::RunStatus::ok || r.status == sim::RunStatus::rail_miss));
    (r.status == sim::RunStatus::ok ? entry : miss) = mid;
    (r.status == sim::RunStatus::ok ? re : rm) = std::move(r);
  }
  INFO("l_0 in [" << miss << ", " << entry << "]: margins " << rm.rail_margin_m << ", " << re.rail_margin_m << " m");
  CHECK(rm.rail_margin_m < 0.0);
  CHECK(re.rail_margin_m > 0.0);
  CHECK(-rm.rail_margin_m < 3 * (entry - miss));
  CHECK(re.rail_margin_m < 3 * (entry - miss));
  // The held stack has no rail miss: no margin; nor has the free stack's stage of bay 1, whose
  // lower frame 0 is held (a one-bay free mast enters the rail and has no margin, two bays have one).
  CHECK(std::isnan(sim::simulate(load("table1.toml", {"run.output_step_s=0"})).rail_margin_m));
  for (const int n : {1, 2}) {
    const sim::RunResult r = sim::simulate(load("paper_free.toml", {"stack.contacts=false", "run.output_step_s=0",
                                                                   "mast.diagonal_free_length_m=0.49",
                                                                   fmt::format("mast.n_bays={}", n)}));
    REQUIRE(r.status == sim::RunStatus::ok);
    CHECK(std::isnan(r.rail_margin_m) == (n == 1));
  }
}

namespace {
sim::RunResult run_free_l0(double l0) {
  return sim::simulate(load("paper_free.toml", {"stack.contacts=false", "run.output_step_s=0",
                                                "mast.diagonal_free_length_m=" + fmt::format("{}", l0)}));
}
}  // namespace

// No plateau (docs/model-notes.md "Rail margin"): from diagonals slack at every entry (l_0 >= 0.4781 m)
// through taut ones to the miss (l_0 < 0.47043 m) the margin rises strictly with l_0, and it is
// <= 0 exactly on the misses. Where the diagonals are slack at entry the motion does not depend on
// l_0, so the margin moves only with the slack, at d^2 / (d + s)^2 <= 1 m per m of l_0.
TEST_CASE("rail_margin_m rises strictly with the diagonal free length, slack diagonals included",
          "[regression][free]") {
  const std::vector<double> l0s = {0.466, 0.470, 0.4704, 0.4706, 0.472, 0.475, 0.477, 0.478,
                                   0.4782, 0.479, 0.48, 0.485, 0.49, 0.50, 0.52};
  std::vector<double> margin;
  for (const double l0 : l0s) {
    const sim::RunResult r = run_free_l0(l0);
    INFO("l_0 " << l0 << " m: " << sim::to_string(r.status) << ", margin " << r.rail_margin_m << " m");
    REQUIRE((r.status == sim::RunStatus::ok || r.status == sim::RunStatus::rail_miss));
    CHECK((r.rail_margin_m <= 0.0) == (r.status == sim::RunStatus::rail_miss));
    if (!margin.empty()) CHECK(r.rail_margin_m > margin.back());
    if (l0 > 0.4782) CHECK(r.rail_margin_m - margin.back() <= l0 - l0s[margin.size() - 1]);  // slope <= 1
    margin.push_back(r.rail_margin_m);
  }
}

// Continuity where the diagonals go taut at the entry. In velocity mode the driven frame of stage m
// is at y_m = y_s + v (t_entry - t_start) at its entry (y_s: 0 for bay n, else y_r - l where the
// lock of bay m + 1 left it at t_start), and the pin on the rail line puts it at
// Y(x) = y_r - c x + sqrt(l^2 - x^2): so x and the opening D = 2 sqrt(l^2 - x^2) at the entry follow
// from the run's entry and lock times alone, and the diagonals are taut at the entry for
// l_0 < L = sqrt(b^2 + D^2). With every diagonal slack (l_0 = 0.5 m) that L is the transition of
// stage m; at the highest one (bay 2's, 0.47807 m) the run's margin has its kink: steep below
// (the dip falls, about 33 m per m), 1 m per m above. With one-sided slopes s_b, s_a from the
// differences at h and 2h, a continuous margin has m(L + h) - m(L - h) = h (s_b + s_a) + O(h^2),
// and a jump J adds J. At h = 1e-6 m the O(h^2) term, the margin's integration noise (a few 1e-9 m
// at rtol 1e-8) and the error of L (1e-10 m from the event times) leave about 1e-8 m, 3e-4 of
// h (s_b + s_a): the test allows 1e-2 of it, so a jump above 3e-7 m fails it.
TEST_CASE("rail_margin_m is continuous where the diagonals go taut at the entry", "[regression][free]") {
  const sim::RunResult slack = run_free_l0(0.5);
  REQUIRE(slack.status == sim::RunStatus::ok);
  const double beta = 20.85 * M_PI / 180.0, c = 1.0 / std::tan(beta), yr = 0.15 + 0.08 * c, l = 0.18, v = 0.1;
  const int n = slack.n_bays;
  double taut_at = 0.0;
  int taut_bay = 0;
  for (int m = 2; m <= n; ++m) {
    const double te = slack.bays[m - 1].entry_time_s;
    const double ym = m == n ? v * te : yr - l + v * (te - slack.bays[m].lock_time_s);
    double lo = 0.0, hi = l;  // Y(x) falls from y_r + l at x = 0
    for (int i = 0; i < 200; ++i) {
      const double x = 0.5 * (lo + hi);
      (yr - c * x + std::sqrt(l * l - x * x) > ym ? lo : hi) = x;
    }
    const double x = 0.5 * (lo + hi), D = 2.0 * std::sqrt(l * l - x * x), L = std::sqrt(0.36 * 0.36 + D * D);
    if (L > taut_at) taut_at = L, taut_bay = m;
  }
  INFO("the diagonals of bay " << taut_bay << " go taut at the entry below l_0 = " << fmt::format("{:.10f}", taut_at) << " m");
  const double h = 1e-6;
  double mh[5];  // margins at L - 2h, L - h, (unused), L + h, L + 2h
  for (int k : {0, 1, 3, 4}) {
    const sim::RunResult r = run_free_l0(taut_at + (k - 2) * h);
    REQUIRE(r.status == sim::RunStatus::ok);
    mh[k] = r.rail_margin_m;
  }
  const double sb = (mh[1] - mh[0]) / h, sa = (mh[4] - mh[3]) / h, jump = mh[3] - mh[1];
  INFO("slopes " << sb << " below, " << sa << " above (m per m); m(L + h) - m(L - h) = " << jump << " m");
  CHECK(sa > 0.0);
  CHECK(sa <= 1.0 + 1e-2);  // the slack's slope (noise 1e-2 of it at h)
  CHECK(sb > 2.0 * sa);     // the kink: the transition is where the entry times put it
  CHECK(std::abs(jump - h * (sb + sa)) < 1e-2 * h * (sb + sa));
}

// The margin against the miss boundary in a geometric parameter that carries the diagonals from
// slack at every entry to taut and on to a miss: the frame side b_f at l_0 = 0.49 m (a diagonal's
// length is sqrt(b_f^2 + D^2)). While the diagonals are slack the entries do not depend on b_f
// (no force does), so the largest entry opening, bay 2's D_e = 0.31457 m (the continuity test
// above), puts the last slack entry at b_f = sqrt(0.49^2 - D_e^2) = 0.3757 m: the values below it
// are on the slack side, where the margin falls only through the slack s = l_0 - sqrt(b_f^2 + D_e^2),
// at d^2 / (d + s)^2 * b_f / L <= 1 m per m of b_f. Across the scan the margin falls strictly and is
// <= 0 exactly on the misses; the boundary is then bisected on the run's status alone, to 2e-7 m,
// and both sides' margins lie within 3 brackets of zero (the margin moves 0.6-0.9 m per m of b_f
// next to the boundary, its integration noise is a few 1e-9 m): a margin that stayed finite at a
// grazing entry, or a miss whose margin were not its closest approach, would fail it.
TEST_CASE("rail_margin_m against the miss boundary bisected in the frame side", "[regression][free]") {
  auto run = [](double b) {
    return sim::simulate(load("paper_free.toml", {"stack.contacts=false", "run.output_step_s=0",
                                                  "mast.diagonal_free_length_m=0.49",
                                                  "mast.frame_side_m=" + fmt::format("{}", b)}));
  };
  const std::vector<double> bs = {0.30, 0.33, 0.35, 0.36, 0.37, 0.375, 0.378, 0.38, 0.385, 0.39, 0.40};
  std::vector<double> margin;
  double miss = 0.0, entry = 0.0;
  for (const double b : bs) {
    const sim::RunResult r = run(b);
    INFO("b_f " << b << " m: " << sim::to_string(r.status) << ", margin " << r.rail_margin_m << " m");
    REQUIRE((r.status == sim::RunStatus::ok || r.status == sim::RunStatus::rail_miss));
    CHECK((r.rail_margin_m <= 0.0) == (r.status == sim::RunStatus::rail_miss));
    if (!margin.empty()) CHECK(r.rail_margin_m < margin.back());
    if (b <= 0.375 && !margin.empty()) CHECK(margin.back() - r.rail_margin_m <= b - bs[margin.size() - 1]);
    if (r.status == sim::RunStatus::ok) entry = b;
    if (r.status == sim::RunStatus::rail_miss && miss == 0.0) miss = b;
    margin.push_back(r.rail_margin_m);
  }
  REQUIRE(entry > 0.375);  // the scan holds slack entries, taut ones and misses
  REQUIRE(miss > entry);
  sim::RunResult re = run(entry), rm = run(miss);
  while (miss - entry > 2e-7) {
    const double mid = 0.5 * (miss + entry);
    sim::RunResult r = run(mid);
    REQUIRE((r.status == sim::RunStatus::ok || r.status == sim::RunStatus::rail_miss));
    (r.status == sim::RunStatus::ok ? entry : miss) = mid;
    (r.status == sim::RunStatus::ok ? re : rm) = std::move(r);
  }
  INFO("b_f in [" << fmt::format("{:.8f}, {:.8f}", entry, miss) << "] m: margins " << re.rail_margin_m << ", "
                  << rm.rail_margin_m << " m");
  CHECK(re.rail_margin_m > 0.0);
  CHECK(rm.rail_margin_m < 0.0);
  CHECK(re.rail_margin_m < 3 * (miss - entry));
  CHECK(-rm.rail_margin_m < 3 * (miss - entry));
}
