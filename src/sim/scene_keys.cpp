#include "sim/scene_keys.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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

std::vector<SceneKey> make_table() {
  // Enumeration values are listed in the order of the enumerators (sim/scene.hpp, model/drive.hpp,
  // integrators/ode.hpp).
  return {
      TRUSS_INT(mast, n_bays, "1", "number of bays", kRun),
      TRUSS_BAY(TRUSS_REAL(mast, strut_length_m, "m", "m, l_s, length of each of the two struts of a longeron", kBay), strut_length_m),
      TRUSS_BAY(TRUSS_REAL(mast, strut_mass_kg, "kg", "kg, m_s, mass of one strut", kBay), strut_mass_kg),
      TRUSS_BAY(TRUSS_OPT_REAL(mast, strut_inertia_kg_m2, "kg m^2", "kg m^2, J_c, centroidal strut inertia; unset = m_s l_s^2 / 12",
                               kBay, s.mast.calc_strut_inertia_kg_m2()), strut_inertia_kg_m2),
      TRUSS_FRAME(TRUSS_REAL(mast, frame_side_m, "m", "m, b_f, side of the triangular frame", kFrame), side_m),
      TRUSS_FRAME(TRUSS_REAL(mast, frame_mass_kg, "kg", "kg, m_f, mass of one frame", kFrame), mass_kg),
      TRUSS_BAY(TRUSS_REAL(mast, diagonal_stiffness_N_per_m, "N/m", "N/m, K, stiffness of one diagonal", kBay), diagonal_stiffness_N_per_m),
      TRUSS_BAY(TRUSS_REAL(mast, diagonal_free_length_m, "m", "m, l_0, free length of one diagonal", kBay), diagonal_free_length_m),
      TRUSS_OPT_REAL(mast, tip_mass_kg, "kg", "kg, tip fitting; unset = 6 m_s + m_f", kRun, s.mast.calc_tip_mass_kg()),
      TRUSS_REAL(rail, x_m, "m", "m, x_l, rail foot offset from the longeron line", kRun),
      TRUSS_REAL(rail, y_m, "m", "m, y_l, rail foot height", kRun),
      TRUSS_REAL(rail, beta_deg, "deg", "deg, rail inclination to the mast axis, in (0, 90)", kRun),
      TRUSS_ENUM(drive, mode, "\"velocity\" | \"torque\" | \"motor\"", "velocity", "torque", "motor"),
      TRUSS_REAL(drive, speed_m_per_s, "m/s", "m/s, v_dep, driven frame speed (velocity mode)", kRun),
      TRUSS_REAL(drive, screw_lead_m, "m", "m, h, lead of the drive screw", kRun),
      TRUSS_REAL(drive, torque_Nm, "Nm", "N m, constant screw torque (torque mode)", kRun),
      TRUSS_REAL(drive, stall_torque_Nm, "Nm", "N m, motor stall torque (motor mode)", kRun),
      TRUSS_REAL(drive, no_load_speed_rad_per_s, "rad/s", "rad/s, motor no-load speed (motor mode)", kRun),
      TRUSS_ENUM(stack, mode, "\"held\" | \"free\"", "held", "free"),
      TRUSS_INT(panels, count, "1", "number of solar panels, 0 = none, else even", kFixed),
      TRUSS_REAL(panels, length_m, "m", "m, l_p, panel length", kRun),
      TRUSS_REAL(panels, mass_kg, "kg", "kg, m_p, mass of one panel", kRun),
      TRUSS_OPT_REAL(panels, tip_height_m, "m", "m, h_tip, blanket attachment above the top frame; unset = 2 l_s", kRun,
                     s.panels.calc_tip_height_m(s.mast.strut_length_m)),
      TRUSS_ENUM(run, direction, "\"deploy\" | \"retract\"", "deploy", "retract"),
      TRUSS_REAL(run, output_step_s, "s", "s, time-history sample step, 0 = no histories", kFixed),
      TRUSS_REAL(run, rtol, "1", "1, relative tolerance of the ODE integrators", kFixed),
      TRUSS_REAL(run, atol, "1", "absolute tolerance (m, m/s, J) of the ODE integrators", kFixed),
      TRUSS_ENUM(run, integrator, "\"dopri54\" | \"cvode\" (BDF) | \"cvode_adams\" | \"auto\"", "dopri54", "cvode", "cvode_adams", "auto"),
      TRUSS_INT(run, max_steps, "1", "cap on accepted integrator steps over the run", kFixed),
      TRUSS_REAL(run, max_wall_time_s, "s", "s, wall-time cap for one run", kFixed),
      TRUSS_INT(run, max_history_rows, "1", "cap on time-history rows kept in memory (86 B a row); beyond it the history step doubles and every other row is dropped", kFixed),
  };
}

#undef TRUSS_REAL
#undef TRUSS_OPT_REAL
#undef TRUSS_INT
#undef TRUSS_ENUM
#undef TRUSS_BAY
#undef TRUSS_FRAME

}  // namespace

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
