// The scene key table (sim/scene_keys.hpp) against fields set by hand: each accessor reads and
// writes its own SceneOptions field and no other, each per-bay / per-frame key writes its own
// BayParams / FrameParams field, scopes and units are the ones the campaign layer relied on.
#include <catch2/catch.hpp>

#include <cstring>

#include "sim/scene_keys.hpp"

using namespace truss;
using Catch::Detail::Approx;

namespace {
// Byte image of the scene, to see which bytes an accessor changed.
std::vector<unsigned char> bytes_of(const sim::SceneOptions& s) {
  std::vector<unsigned char> b;
  auto put = [&](const auto& v) {
    const auto* p = reinterpret_cast<const unsigned char*>(&v);
    b.insert(b.end(), p, p + sizeof(v));
  };
  put(s.mast.n_bays); put(s.mast.strut_length_m); put(s.mast.strut_mass_kg); put(s.mast.strut_inertia_kg_m2.value_or(-1));
  put(s.mast.frame_side_m); put(s.mast.frame_mass_kg); put(s.mast.diagonal_stiffness_N_per_m);
  put(s.mast.diagonal_free_length_m); put(s.mast.tip_mass_kg.value_or(-1)); put(s.rail.x_m); put(s.rail.y_m);
  put(s.rail.beta_deg); put(s.drive.mode); put(s.drive.speed_m_per_s); put(s.drive.screw_lead_m); put(s.drive.torque_Nm);
  put(s.drive.stall_torque_Nm); put(s.drive.no_load_speed_rad_per_s); put(s.stack.mode); put(s.stack.contacts); put(s.stack.contact_law); put(s.stack.start); put(s.panels.count);
  put(s.panels.length_m); put(s.panels.mass_kg); put(s.panels.tip_height_m.value_or(-1)); put(s.run.direction);
  put(s.run.output_step_s); put(s.run.rtol); put(s.run.atol); put(s.run.integrator); put(s.run.max_steps);
  put(s.run.max_wall_time_s); put(s.run.max_history_bytes);
  put(s.drive.gear_ratio); put(s.drive.gear_efficiency); put(s.drive.screw_efficiency); put(s.drive.screw_back_efficiency);
  put(s.drive.friction_torque_Nm); put(s.drive.detent_torque_Nm); put(s.drive.hysteresis_torque_Nm);
  put(s.drive.harness_torque_Nm); put(s.drive.motor_derating);
  const auto& f = s.motorisation;
  put(f.factor); put(f.spring_factor); put(f.inertia_factor); put(f.friction_factor); put(f.detent_factor);
  put(f.hysteresis_factor); put(f.harness_factor);
  return b;
}
}  // namespace

TEST_CASE("scene key table: each accessor writes its own field, by name", "[unit][keys]") {
  const auto& keys = sim::scene_keys();
  REQUIRE(keys.size() == 50);  // every field of SceneOptions above has one row
  const sim::SceneOptions base;
  for (const auto& k : keys) {
    sim::SceneOptions s;
    INFO(k.dotted());
    if (k.kind == sim::KeyKind::enumeration && k.allowed.size() < 2) continue;  // one value (stack.contact_law): nothing to change
    if (k.kind == sim::KeyKind::enumeration) k.set_enum(s, 1);
    else if (k.kind == sim::KeyKind::integer) k.set_int(s, 7);
    else k.set_real(s, 0.123);
    int changed = 0;
    const auto a = bytes_of(base), b = bytes_of(s);
    for (std::size_t i = 0; i < a.size(); ++i) changed += a[i] != b[i];
    CHECK(changed > 0);
    // the changed value reads back
    if (k.kind == sim::KeyKind::real) CHECK(k.get_real(s) == 0.123);
    if (k.kind == sim::KeyKind::opt_real) CHECK(k.get_opt(s) == 0.123);
    if (k.kind == sim::KeyKind::integer) CHECK(k.get_int(s) == 7);
    if (k.kind == sim::KeyKind::enumeration) CHECK(k.get_enum(s) == 1);
  }
  // A few by hand, independently of the table.
  sim::SceneOptions s;
  sim::find_scene_key("mast.strut_mass_kg")->set_real(s, 0.25);
  CHECK(s.mast.strut_mass_kg == 0.25);
  CHECK(s.mast.frame_mass_kg == base.mast.frame_mass_kg);
  sim::find_scene_key("drive.no_load_speed_rad_per_s")->set_real(s, 12.0);
  CHECK(s.drive.no_load_speed_rad_per_s == 12.0);
  sim::find_scene_key("run.integrator")->set_enum(s, 1);
  CHECK(s.run.integrator == sim::IntegratorKind::cvode);
  sim::find_scene_key("mast.n_bays")->set_real(s, 11.6);  // a dispersed bay count rounds
  CHECK(s.mast.n_bays == 12);
  sim::find_scene_key("stack.contacts")->set_enum(s, 1);
  CHECK(s.stack.contacts == sim::StackContacts::on);
  sim::find_scene_key("stack.start")->set_enum(s, 1);
  CHECK(s.stack.start == sim::StackStart::rest);
  sim::find_scene_key("drive.screw_back_efficiency")->set_real(s, 0.3);
  CHECK(s.drive.screw_back_efficiency == 0.3);
  CHECK(s.drive.screw_efficiency == base.drive.screw_efficiency);
  sim::find_scene_key("motorisation.harness_factor")->set_real(s, 1.5);
  CHECK(s.motorisation.harness_factor == 1.5);
  CHECK(s.motorisation.friction_factor == base.motorisation.friction_factor);
}

TEST_CASE("scene key table: resolved values of the optional keys are the derived defaults", "[unit][keys]") {
  sim::SceneOptions s;
  s.mast.strut_mass_kg = 0.2;
  s.mast.strut_length_m = 0.3;
  s.mast.frame_mass_kg = 0.7;
  CHECK(sim::find_scene_key("mast.strut_inertia_kg_m2")->get_real(s) == Approx(0.2 * 0.09 / 12.0).epsilon(1e-15));
  CHECK(sim::find_scene_key("mast.tip_mass_kg")->get_real(s) == Approx(6 * 0.2 + 0.7).epsilon(1e-15));
  CHECK(sim::find_scene_key("panels.tip_height_m")->get_real(s) == Approx(0.6).epsilon(1e-15));
  CHECK_FALSE(sim::find_scene_key("mast.tip_mass_kg")->get_opt(s).has_value());
}

TEST_CASE("scene key table: dispersion scopes, mast fields and units", "[unit][keys]") {
  const char* bay_keys[] = {"mast.strut_length_m", "mast.strut_mass_kg", "mast.strut_inertia_kg_m2",
                            "mast.diagonal_stiffness_N_per_m", "mast.diagonal_free_length_m"};
  for (const char* name : bay_keys) {
    const auto* k = sim::find_scene_key(name);
    REQUIRE(k);
    CHECK(k->scope == sim::KeyScope::bay);
    model::BayParams b;
    *k->bay_field(b) = -5.0;
    const model::BayParams ref;
    const int changed = (b.strut_length_m != ref.strut_length_m) + (b.strut_mass_kg != ref.strut_mass_kg) +
                        (b.strut_inertia_kg_m2 != ref.strut_inertia_kg_m2) +
                        (b.diagonal_stiffness_N_per_m != ref.diagonal_stiffness_N_per_m) +
                        (b.diagonal_free_length_m != ref.diagonal_free_length_m);
    CHECK(changed == 1);
  }
  // Each per-bay key against its field, named by hand.
  model::BayParams b;
  CHECK(sim::find_scene_key("mast.strut_length_m")->bay_field(b) == &b.strut_length_m);
  CHECK(sim::find_scene_key("mast.strut_mass_kg")->bay_field(b) == &b.strut_mass_kg);
  CHECK(sim::find_scene_key("mast.strut_inertia_kg_m2")->bay_field(b) == &b.strut_inertia_kg_m2);
  CHECK(sim::find_scene_key("mast.diagonal_stiffness_N_per_m")->bay_field(b) == &b.diagonal_stiffness_N_per_m);
  CHECK(sim::find_scene_key("mast.diagonal_free_length_m")->bay_field(b) == &b.diagonal_free_length_m);
  model::FrameParams f;
  *sim::find_scene_key("mast.frame_side_m")->frame_field(f) = 0.4;
  *sim::find_scene_key("mast.frame_mass_kg")->frame_field(f) = 0.9;
  CHECK(f.side_m == 0.4);
  CHECK(f.mass_kg == 0.9);
  // The per-run dispersible keys and the fixed ones, listed by hand (the campaign layer's former sets).
  const char* run_keys[] = {"mast.n_bays", "mast.tip_mass_kg", "rail.x_m", "rail.y_m", "rail.beta_deg",
                            "drive.speed_m_per_s", "drive.screw_lead_m", "drive.torque_Nm", "drive.stall_torque_Nm",
                            "drive.no_load_speed_rad_per_s", "panels.length_m", "panels.mass_kg", "panels.tip_height_m",
                            "drive.gear_ratio", "drive.gear_efficiency", "drive.screw_efficiency", "drive.screw_back_efficiency",
                            "drive.friction_torque_Nm", "drive.detent_torque_Nm", "drive.hysteresis_torque_Nm",
                            "drive.harness_torque_Nm", "drive.motor_derating"};
  for (const char* name : run_keys) CHECK(sim::find_scene_key(name)->scope == sim::KeyScope::run);
  int n_fixed = 0;
  for (const auto& k : sim::scene_keys()) n_fixed += !k.is_dispersible();
  CHECK(n_fixed == 50 - 22 - 5 - 2);  // the [motorisation] factors are fixed
  for (const char* name : {"panels.count", "run.rtol", "drive.mode", "stack.mode", "run.max_steps", "motorisation.factor"})
    CHECK_FALSE(sim::find_scene_key(name)->is_dispersible());
  CHECK(sim::find_scene_key("mast.strut_inertia_kg_m2")->unit == "kg m^2");
  CHECK(sim::find_scene_key("mast.diagonal_stiffness_N_per_m")->unit == "N/m");
  CHECK(sim::find_scene_key("drive.no_load_speed_rad_per_s")->unit == "rad/s");
  CHECK(sim::find_scene_key("drive.harness_torque_Nm")->unit == "Nm");
  CHECK(sim::find_scene_key("drive.motor_derating")->unit == "1");
  CHECK(sim::find_scene_key("motorisation.spring_factor")->unit == "1");
  CHECK(sim::find_scene_key("mast.wing_span_m") == nullptr);
  CHECK(sim::find_scene_key("mast") == nullptr);
}
