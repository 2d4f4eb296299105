// Reads a truss-sim scene file into MastScene (see scene.hpp). Every key of the shipped scenes is
// known: the mast/rail/drive keys are used, the integrator and output keys of truss-sim's own
// numerics (run.integrator, run.atol, run.output_step_s, caps) are accepted and not used, and a
// setting this model does not represent is refused.
#include "scene.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <functional>
#include <map>
#include <sstream>

namespace mastcheck {
namespace {

using Setter = std::function<void(MastScene&, const toml::node&, const std::string& where)>;

[[noreturn]] void fail(const std::string& where, const std::string& why) {
  throw SceneError("error: " + where + ": " + why);
}

double as_number(const toml::node& v, const std::string& where) {
  if (auto d = v.value<double>()) return *d;
  fail(where, "expected a number");
}
std::string as_string(const toml::node& v, const std::string& where) {
  if (auto s = v.value<std::string>()) return *s;
  fail(where, "expected a string");
}

Setter number(double MastScene::*field, double lo, double hi) {
  return [=](MastScene& s, const toml::node& v, const std::string& where) {
    const double x = as_number(v, where);
    if (!std::isfinite(x) || x <= lo || x > hi) fail(where, "out of range");
    s.*field = x;
  };
}
Setter accepted() {  // truss-sim's own numerics or output: no meaning for this model
  return [](MastScene&, const toml::node&, const std::string&) {};
}
// A drive-train key: this model has the ideal train only (the paper's drive), so the key is
// accepted at its ideal value and refused at any other.
Setter ideal_only(double ideal) {
  return [=](MastScene&, const toml::node& v, const std::string& where) {
    if (as_number(v, where) == ideal) return;
    std::ostringstream os;
    os << "the Simbody check models the ideal drive train only (" << ideal << ")";
    fail(where, os.str());
  };
}

const std::map<std::string, Setter>& keys() {
  static const std::map<std::string, Setter> table = {
      {"mast.n_bays", [](MastScene& s, const toml::node& v, const std::string& w) {
         auto n = v.value<int64_t>();
         if (!n || *n < 1 || *n > 1000) fail(w, "expected an integer in 1..1000");
         s.n_bays = static_cast<int>(*n);
       }},
      {"mast.strut_length_m", number(&MastScene::strut_length_m, 0, 100)},
      {"mast.strut_mass_kg", number(&MastScene::strut_mass_kg, 0, 1e6)},
      {"mast.strut_inertia_kg_m2", number(&MastScene::strut_inertia_kg_m2, 0, 1e6)},
      {"mast.frame_side_m", number(&MastScene::frame_side_m, 0, 100)},
      {"mast.frame_mass_kg", number(&MastScene::frame_mass_kg, 0, 1e6)},
      {"mast.diagonal_stiffness_N_per_m", number(&MastScene::diagonal_stiffness_N_per_m, -1e-300, 1e12)},
      {"mast.diagonal_free_length_m", number(&MastScene::diagonal_free_length_m, 0, 100)},
      {"mast.tip_mass_kg", number(&MastScene::tip_mass_kg, -1e-300, 1e6)},
      {"rail.x_m", number(&MastScene::rail_x_m, -1e-300, 100)},
      {"rail.y_m", number(&MastScene::rail_y_m, -1e-300, 100)},
      {"rail.beta_deg", number(&MastScene::rail_beta_deg, 0, 89.999)},
      {"drive.mode", [](MastScene& s, const toml::node& v, const std::string& w) {
         const std::string m = as_string(v, w);
         if (m == "velocity") s.drive = DriveMode::velocity;
         else if (m == "torque") s.drive = DriveMode::torque;
         else if (m == "motor") s.drive = DriveMode::motor;
         else fail(w, "expected \"velocity\", \"torque\" or \"motor\"");
       }},
      {"drive.speed_m_per_s", number(&MastScene::speed_m_per_s, 0, 1e3)},
      {"drive.screw_lead_m", number(&MastScene::screw_lead_m, 0, 10)},
      {"drive.torque_Nm", number(&MastScene::torque_Nm, 0, 1e6)},
      {"drive.stall_torque_Nm", number(&MastScene::stall_torque_Nm, 0, 1e6)},
      {"drive.no_load_speed_rad_per_s", number(&MastScene::no_load_speed_rad_per_s, 0, 1e6)},
      {"drive.gear_ratio", ideal_only(1.0)},
      {"drive.gear_efficiency", ideal_only(1.0)},
      {"drive.screw_efficiency", ideal_only(1.0)},
      {"drive.screw_back_efficiency", ideal_only(1.0)},
      {"drive.friction_torque_Nm", ideal_only(0.0)},
      {"drive.detent_torque_Nm", ideal_only(0.0)},
      {"drive.hysteresis_torque_Nm", ideal_only(0.0)},
      {"drive.harness_torque_Nm", ideal_only(0.0)},
      {"drive.motor_derating", ideal_only(1.0)},
      // The motorisation check is arithmetic on a run's outputs, not dynamics.
      {"motorisation.factor", accepted()},
      {"motorisation.spring_factor", accepted()},
      {"motorisation.inertia_factor", accepted()},
      {"motorisation.friction_factor", accepted()},
      {"motorisation.detent_factor", accepted()},
      {"motorisation.hysteresis_factor", accepted()},
      {"motorisation.harness_factor", accepted()},
      // Structural allowables and factors: arithmetic on the design loads, not dynamics.
      {"structure.yield_factor", accepted()},
      {"structure.ultimate_factor", accepted()},
      {"structure.pin_force_yield_allowable_N", accepted()},
      {"structure.pin_force_ultimate_allowable_N", accepted()},
      {"structure.diagonal_tension_yield_allowable_N", accepted()},
      {"structure.diagonal_tension_ultimate_allowable_N", accepted()},
      {"structure.latch_energy_yield_allowable_J", accepted()},
      {"structure.latch_energy_ultimate_allowable_J", accepted()},
      {"structure.screw_force_yield_allowable_N", accepted()},
      {"structure.screw_force_ultimate_allowable_N", accepted()},
      {"structure.drive_force_yield_allowable_N", accepted()},
      {"structure.drive_force_ultimate_allowable_N", accepted()},
      {"stack.mode", [](MastScene& s, const toml::node& v, const std::string& w) {
         const std::string m = as_string(v, w);
         if (m != "held" && m != "free") fail(w, "expected \"held\" or \"free\"");
         s.free_stack = (m == "free");
       }},
      {"stack.contacts", [](MastScene&, const toml::node& v, const std::string& w) {
         auto b = v.value<bool>();
         if (!b) fail(w, "expected true or false");
         if (*b) fail(w, "stack contacts are not modelled in the Simbody check (false only)");
       }},
      {"stack.contact_law", accepted()},
      {"panels.count", [](MastScene&, const toml::node& v, const std::string& w) {
         if (v.value<int64_t>().value_or(-1) != 0)
           fail(w, "the solar blanket is not modelled in the Simbody check (0 only)");
       }},
      {"panels.length_m", accepted()},
      {"panels.mass_kg", accepted()},
      {"panels.tip_height_m", accepted()},
      {"run.direction", [](MastScene&, const toml::node& v, const std::string& w) {
         if (as_string(v, w) != "deploy") fail(w, "the Simbody check runs deployments only (\"deploy\")");
       }},
      {"run.rtol", number(&MastScene::rtol, 0, 0.1)},
      {"run.atol", accepted()},
      {"run.output_step_s", accepted()},
      {"run.integrator", accepted()},
      {"run.max_steps", accepted()},
      {"run.max_wall_time_s", accepted()},
  };
  return table;
}

void apply(MastScene& scene, const std::string& key, const toml::node& value, const std::string& where) {
  const auto it = keys().find(key);
  if (it == keys().end()) fail(where, "unknown key " + key);
  if (value.is_array()) fail(where + ": " + key, "per-bay arrays are not supported by the Simbody check");
  it->second(scene, value, where + ": " + key);
}

// An override "table.key=value" as a one-key document (the value is TOML; a bare word a string).
toml::table parse_override(const std::string& assignment, std::string& key) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos) fail("--set " + assignment, "expected table.key=value");
  key = assignment.substr(0, eq);
  const std::string text = assignment.substr(eq + 1);
  try {
    return toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    return toml::table{{"v", text}};
  }
}

}  // namespace

MastScene read_scene(const std::string& path, const std::vector<std::string>& overrides) {
  toml::table root;
  try {
    root = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream msg;
    msg << e.description() << " (line " << e.source().begin.line << ")";
    fail(path, msg.str());
  }
  // Every setting, the file's first, an override replacing the file's value; then applied.
  std::map<std::string, std::pair<const toml::node*, std::string>> settings;
  for (const auto& [table_name, table] : root) {
    if (!table.is_table()) fail(path, "top-level key " + std::string(table_name.str()) + " is not a table");
    for (const auto& [key, value] : *table.as_table())
      settings[std::string(table_name.str()) + "." + std::string(key.str())] = {
          &value, path + ":" + std::to_string(value.source().begin.line)};
  }
  std::vector<toml::table> override_docs;
  override_docs.reserve(overrides.size());
  for (const auto& o : overrides) {
    std::string key;
    override_docs.push_back(parse_override(o, key));
    settings[key] = {override_docs.back().get("v"), "--set " + o};
  }
  MastScene scene;
  for (const auto& [key, setting] : settings) apply(scene, key, *setting.first, setting.second);
  return scene;
}

}  // namespace mastcheck
