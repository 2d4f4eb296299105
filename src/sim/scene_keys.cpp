#include "sim/scene_keys.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace truss::sim {

namespace {

// Row builders. T, K: the member names of SceneOptions (table.key); U: unit; C: comment;
// S: dispersion scope.
#define TRUSS_REAL(T, K, U, C, S)                                               \
  SceneKey {                                                                    \
    #T, #K, KeyKind::real, U, C, S, {}, 0, 0,                                   \
        [](SceneOptions& s, double v) { s.T.K = v; },                           \
        [](const SceneOptions& s) -> double { return s.T.K; }                   \
  }
#define TRUSS_OPT_REAL(T, K, U, C, S, RESOLVED)                                                 \
  SceneKey {                                                                                    \
    #T, #K, KeyKind::opt_real, U, C, S, {}, 0, 0,                                               \
        [](SceneOptions& s, double v) { s.T.K = v; },                                           \
        [](const SceneOptions& s) -> double { return RESOLVED; },                               \
        [](const SceneOptions& s) -> std::optional<double> { return s.T.K; }                    \
  }
#define TRUSS_INT(T, K, U, C, S)                                                                \
  SceneKey {                                                                                    \
    #T, #K, KeyKind::integer, U, C, S, {},                                                      \
        static_cast<std::int64_t>(std::numeric_limits<decltype(SceneOptions{}.T.K)>::min()),    \
        static_cast<std::int64_t>(std::numeric_limits<decltype(SceneOptions{}.T.K)>::max()),    \
        [](SceneOptions& s, double v) { s.T.K = static_cast<decltype(s.T.K)>(std::lround(v)); }, \
        [](const SceneOptions& s) -> double { return s.T.K; }, nullptr,                         \
        [](SceneOptions& s, std::int64_t v) { s.T.K = static_cast<decltype(s.T.K)>(v); },       \
        [](const SceneOptions& s) -> std::int64_t { return s.T.K; }                             \
  }
#define TRUSS_ENUM(T, K, C, ...)                                                                  \
  SceneKey {                                                                                      \
    #T, #K, KeyKind::enumeration, "1", C, KeyScope::fixed, {__VA_ARGS__}, 0, 0, nullptr, nullptr, \
        nullptr, nullptr, nullptr,                                                                \
        [](SceneOptions& s, std::size_t i) { s.T.K = static_cast<decltype(s.T.K)>(i); },          \
        [](const SceneOptions& s) -> std::size_t { return static_cast<std::size_t>(s.T.K); }      \
  }
// Per-bay / per-frame keys also name their field of BayParams / FrameParams.
#define TRUSS_BAY(ROW, F) [] { SceneKey k = ROW; k.bay_field = [](model::BayParams& b) { return &b.F; }; return k; }()
#define TRUSS_FRAME(ROW, F) [] { SceneKey k = ROW; k.frame_field = [](model::FrameParams& f) { return &f.F; }; return k; }()

constexpr KeyScope kFixed = KeyScope::fixed, kRun = KeyScope::run, kBay = KeyScope::bay, kFrame = KeyScope::frame;

// A row with its hard and typical ranges (scene_keys.hpp). P(hi): (0, hi]; C(lo, hi): [lo, hi].
SceneKey R(SceneKey k, KeyRange hard, KeyRange typical) {
  k.hard = hard;
  k.typical = typical;
  return k;
}
constexpr KeyRange P(double hi) { return {0.0, hi, true, false}; }
constexpr KeyRange C(double lo, double hi) { return {lo, hi, false, false}; }

std::vector<SceneKey> make_table() {
  // Enumeration values are listed in the order of the enumerators (sim/scene.hpp, model/drive.hpp,
  // integrators/ode.hpp). Typical ranges: Table 1 and the small masts of the literature (struts of
  // 2 cm to 2 m, frames of 10 g to 50 kg, drives of 0.1 mm/s to 1 m/s and 0.1 mN m to 1 N m).
  return {
      R(TRUSS_INT(mast, n_bays, "1", "number of bays", kRun), C(1, 100000), C(1, 1000)),
      R(TRUSS_BAY(TRUSS_REAL(mast, strut_length_m, "m", "m, l_s, length of each of the two struts of a longeron", kBay), strut_length_m),
        P(1e3), C(0.02, 2)),
      R(TRUSS_BAY(TRUSS_REAL(mast, strut_mass_kg, "kg", "kg, m_s, mass of one strut", kBay), strut_mass_kg), P(1e4), C(0.005, 5)),
      R(TRUSS_BAY(TRUSS_OPT_REAL(mast, strut_inertia_kg_m2, "kg m^2", "kg m^2, J_c, centroidal strut inertia; unset = m_s l_s^2 / 12",
                                 kBay, s.mast.calc_strut_inertia_kg_m2()), strut_inertia_kg_m2),
        P(1e6), C(1e-8, 2)),
      R(TRUSS_FRAME(TRUSS_REAL(mast, frame_side_m, "m", "m, b_f, side of the triangular frame", kFrame), side_m), P(1e3), C(0.05, 5)),
      R(TRUSS_FRAME(TRUSS_REAL(mast, frame_mass_kg, "kg", "kg, m_f, mass of one frame", kFrame), mass_kg), P(1e5), C(0.01, 50)),
      R(TRUSS_BAY(TRUSS_REAL(mast, diagonal_stiffness_N_per_m, "N/m", "N/m, K, stiffness of one diagonal", kBay), diagonal_stiffness_N_per_m),
        P(1e9), C(0.1, 1e5)),
      R(TRUSS_BAY(TRUSS_REAL(mast, diagonal_free_length_m, "m", "m, l_0, free length of one diagonal", kBay), diagonal_free_length_m),
        P(1e3), C(0.02, 5)),
      R(TRUSS_OPT_REAL(mast, tip_mass_kg, "kg", "kg, tip fitting; unset = 6 m_s + m_f", kRun, s.mast.calc_tip_mass_kg()),
        C(0, 1e5), C(0, 100)),
      R(TRUSS_REAL(rail, x_m, "m", "m, x_l, rail foot offset from the longeron line", kRun), C(-1e3, 1e3), C(-1, 1)),
      R(TRUSS_REAL(rail, y_m, "m", "m, y_l, rail foot height", kRun), C(-1e3, 1e3), C(-1, 1)),
      R(TRUSS_REAL(rail, beta_deg, "deg", "deg, rail inclination to the mast axis, in (0, 90)", kRun), C(-360, 360), C(1, 89)),
      TRUSS_ENUM(drive, mode, "\"velocity\" | \"torque\" | \"motor\"", "velocity", "torque", "motor"),
      R(TRUSS_REAL(drive, speed_m_per_s, "m/s", "m/s, v_dep, driven frame speed (velocity mode)", kRun), P(1e3), C(1e-4, 1)),
      R(TRUSS_REAL(drive, screw_lead_m, "m", "m, h, lead of the drive screw", kRun), P(10), C(1e-4, 0.05)),
      R(TRUSS_REAL(drive, torque_Nm, "Nm", "N m, constant screw torque (torque mode)", kRun), P(1e4), C(1e-4, 1)),
      R(TRUSS_REAL(drive, stall_torque_Nm, "Nm", "N m, motor stall torque (motor mode)", kRun), P(1e4), C(1e-4, 1)),
      R(TRUSS_REAL(drive, no_load_speed_rad_per_s, "rad/s", "rad/s, motor no-load speed (motor mode)", kRun), P(1e6), C(1, 2000)),
      // The drive train (docs/model-notes.md "Drive train"); the defaults are an ideal train.
      R(TRUSS_REAL(drive, gear_ratio, "1", "1, N, motor turns per screw turn (gearbox data sheet); 1 = motor on the screws", kRun),
        P(1e6), C(0.1, 1e4)),
      R(TRUSS_REAL(drive, gear_efficiency, "1", "1, eta_g, gearbox efficiency in (0, 1], either power flow (data sheet)", kRun),
        P(1.0), C(0.05, 1)),
      R(TRUSS_REAL(drive, screw_efficiency, "1",
                   "1, eta_s, lead-screw efficiency driving the load, tan(lambda) / tan(lambda + phi) (power-screw formula)", kRun),
        P(1.0), C(0.05, 1)),
      R(TRUSS_REAL(drive, screw_back_efficiency, "1",
                   "1, eta_s', lead-screw efficiency backdriven (load drives the screw), tan(lambda - phi) / tan(lambda); "
                   "> 0: not self-locking", kRun),
        P(1.0), C(0.05, 1)),
      R(TRUSS_REAL(drive, friction_torque_Nm, "Nm", "N m at the motor shaft, friction against the motion (ECSS F_R)", kRun),
        C(0, 1e4), C(0, 1)),
      R(TRUSS_REAL(drive, detent_torque_Nm, "Nm", "N m at the motor shaft, the motor's detent torque against the motion (ECSS H_M)", kRun),
        C(0, 1e4), C(0, 1)),
      R(TRUSS_REAL(drive, hysteresis_torque_Nm, "Nm", "N m at the motor shaft, hysteresis against the motion (ECSS H_Y)", kRun),
        C(0, 1e4), C(0, 1)),
      R(TRUSS_REAL(drive, harness_torque_Nm, "Nm", "N m at the motor shaft, harness resistance against the motion (ECSS H_A)", kRun),
        C(0, 1e4), C(0, 1)),
      R(TRUSS_REAL(drive, motor_derating, "1",
                   "1, k_d, motor torque derating in (0, 1]: temperature x voltage x end of life (motor data sheet)", kRun),
        P(1.0), C(0.3, 1)),
      TRUSS_ENUM(stack, mode, "\"held\" | \"free\"", "held", "free"),
      TRUSS_ENUM(stack, contacts, "false | true: unilateral stack contacts D_i >= 0 (free stack only)", "false", "true"),
      TRUSS_ENUM(stack, contact_law, "\"plastic\" (landings lose the approach energy)", "plastic"),
      TRUSS_ENUM(stack, start, "\"kick\" | \"rest\": the free frames at the velocity drive's impulsive start (free stack only)",
                 "kick", "rest"),
      R(TRUSS_INT(panels, count, "1", "number of solar panels, 0 = none, else even", kFixed), C(0, 1e5), C(0, 200)),
      R(TRUSS_REAL(panels, length_m, "m", "m, l_p, panel length", kRun), P(1e3), C(0.05, 5)),
      R(TRUSS_REAL(panels, mass_kg, "kg", "kg, m_p, mass of one panel", kRun), P(1e4), C(0.01, 10)),
      R(TRUSS_OPT_REAL(panels, tip_height_m, "m", "m, h_tip, blanket attachment above the top frame; unset = 2 l_s", kRun,
                       s.panels.calc_tip_height_m(s.mast.strut_length_m)),
        P(1e3), C(0.01, 5)),
      TRUSS_ENUM(run, direction, "\"deploy\" | \"retract\"", "deploy", "retract"),
      R(TRUSS_REAL(run, output_step_s, "s", "s, time-history sample step, 0 = no histories", kFixed), C(0, 1e3), C(0, 1)),
      R(TRUSS_REAL(run, rtol, "1", "1, relative tolerance of the ODE integrators", kFixed), C(stages::kMinRtol, stages::kMaxRtol), C(1e-13, 1e-3)),
      R(TRUSS_REAL(run, atol, "1", "absolute tolerance (m, m/s, J) of the ODE integrators", kFixed), P(stages::kMaxAtol), C(1e-15, 1e-4)),
      TRUSS_ENUM(run, integrator, "\"dopri54\" | \"cvode\" (BDF) | \"cvode_adams\" | \"auto\" | \"ida\" (free stack) | \"dop853\"", "dopri54", "cvode", "cvode_adams", "auto", "ida", "dop853"),
      R(TRUSS_INT(run, max_steps, "1", "cap on accepted integrator steps over the run", kFixed), C(1, 1e15), C(1e3, 1e10)),
      R(TRUSS_REAL(run, max_wall_time_s, "s", "s, wall-time cap for one run", kFixed), P(1e7), C(0.01, 86400)),
      R(TRUSS_INT(run, max_history_bytes, "B",
                  "B, cap on the time-history memory (84 B a row, 8 B more per frame with a free stack); at the cap the "
                  "history step doubles and every other row is dropped", kFixed),
        C(1e3, 1e12), C(1e6, 1e10)),
      // The motorisation check, ECSS-E-ST-33-01C 4.7.5.3.1 and Table 4-2 (model/motorisation.hpp).
      R(TRUSS_REAL(motorisation, factor, "1", "1, MF, motorisation factor on the resistances (ECSS-E-ST-33-01C 4.7.5.3.1)", kFixed),
        P(1e3), C(1, 10)),
      R(TRUSS_REAL(motorisation, spring_factor, "1", "1, uncertainty factor of the spring resistance S (Table 4-2)", kFixed),
        P(1e3), C(1, 10)),
      R(TRUSS_REAL(motorisation, inertia_factor, "1", "1, factor of the inertial resistance T_D (4.7.5.3.1)", kFixed), P(1e3), C(1, 10)),
      R(TRUSS_REAL(motorisation, friction_factor, "1", "1, uncertainty factor of friction F_R (Table 4-2; measured: 1.5)", kFixed),
        P(1e3), C(1, 10)),
      R(TRUSS_REAL(motorisation, detent_factor, "1",
                   "1, uncertainty factor of the motor's magnetic losses H_M, its detent (Table 4-2; measured: 1.2)", kFixed),
        P(1e3), C(1, 10)),
      R(TRUSS_REAL(motorisation, hysteresis_factor, "1", "1, uncertainty factor of hysteresis H_Y (Table 4-2; measured: 1.5)", kFixed),
        P(1e3), C(1, 10)),
      R(TRUSS_REAL(motorisation, harness_factor, "1", "1, uncertainty factor of the harness H_A (Table 4-2; measured: 1.5)", kFixed),
        P(1e3), C(1, 10)),
  };
}

#undef TRUSS_REAL
#undef TRUSS_OPT_REAL
#undef TRUSS_INT
#undef TRUSS_ENUM
#undef TRUSS_BAY
#undef TRUSS_FRAME

}  // namespace

std::string KeyRange::text() const {
  return fmt::format("{}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
}

namespace {
// fmt rather than " " + std::string: GCC 12 warns falsely (-Wrestrict) on the inlined operator+.
std::string unit_text(const SceneKey& k) {
  return k.unit == "1" ? "" : fmt::format(" {}", k.unit == "Nm" ? "N m" : k.unit);
}
}  // namespace

std::string check_hard_range(const SceneKey& k, double v) {
  if (k.kind == KeyKind::enumeration || k.hard.contains(v)) return {};
  return fmt::format("{}: must lie in {}{}, got {}", k.dotted(), k.hard.text(), unit_text(k), v);
}

std::string check_typical_range(const SceneKey& k, double v) {
  if (k.kind == KeyKind::enumeration || k.typical.contains(v)) return {};
  std::string hint;
  if (k.typical.contains(v * 1e-3)) hint = fmt::format(" (a value in milli-units? {:.6g}{} would be typical)", v * 1e-3, unit_text(k));
  else if (k.typical.contains(v * 1e3)) hint = fmt::format(" (a value in kilo-units? {:.6g}{} would be typical)", v * 1e3, unit_text(k));
  return fmt::format("{} = {}{} is outside the typical range {}{}{}", k.dotted(), v, unit_text(k), k.typical.text(),
                     unit_text(k), hint);
}

std::optional<double> key_value(const SceneKey& k, const SceneOptions& s) {
  switch (k.kind) {
    case KeyKind::real: return k.get_real(s);
    case KeyKind::opt_real: return k.get_opt(s);
    case KeyKind::integer: return static_cast<double>(k.get_int(s));
    case KeyKind::enumeration: return std::nullopt;
  }
  return std::nullopt;
}

std::string check_scene_ranges(const SceneOptions& s) {
  for (const auto& k : scene_keys())
    if (const auto v = key_value(k, s))
      if (std::string e = check_hard_range(k, *v); !e.empty()) return e;
  return {};
}

std::string check_mast_ranges(const model::MastParams& m) {
  for (const auto& k : scene_keys()) {
    for (std::size_t i = 0; k.bay_field && i < m.bays.size(); ++i) {
      model::BayParams b = m.bays[i];
      if (std::string e = check_hard_range(k, *k.bay_field(b)); !e.empty()) return fmt::format("{} (bay {})", e, i + 1);
    }
    for (std::size_t i = 0; k.frame_field && i < m.frames.size(); ++i) {
      model::FrameParams f = m.frames[i];
      if (std::string e = check_hard_range(k, *k.frame_field(f)); !e.empty()) return fmt::format("{} (frame {})", e, i);
    }
  }
  return {};
}

const std::vector<SceneKey>& scene_keys() {
  static const std::vector<SceneKey> table = make_table();
  return table;
}

const SceneKey* find_scene_key(std::string_view table, std::string_view key) {
  for (const auto& d : scene_keys())
    if (d.table == table && d.key == key) return &d;
  return nullptr;
}

const SceneKey* find_scene_key(std::string_view dotted) {
  const auto dot = dotted.find('.');
  if (dot == std::string_view::npos) return nullptr;
  return find_scene_key(dotted.substr(0, dot), dotted.substr(dot + 1));
}

std::vector<std::string_view> find_scene_tables() {
  std::vector<std::string_view> t;
  for (const auto& d : scene_keys())
    if (std::find(t.begin(), t.end(), d.table) == t.end()) t.push_back(d.table);
  return t;
}

}  // namespace truss::sim
