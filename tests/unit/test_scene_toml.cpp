// Scene TOML parsing: full files, defaults, every class of bad input, --set overrides,
// validate() messages with lines, and the resolved-scene round trip.
#include <catch2/catch.hpp>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "io/scene_toml.hpp"

using truss::io::InputError;
using truss::io::parse_scene_file;
using truss::io::parse_scene_text;
using truss::io::resolved_scene_toml;
using truss::sim::DriveMode;
using truss::sim::Direction;
using truss::sim::IntegratorKind;
using truss::sim::SceneOptions;
using truss::sim::StackMode;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

// The message of the InputError that parsing `text` (named scene.toml) throws; fails the test
// when nothing is thrown.
std::string parse_error(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    parse_scene_text(text, "scene.toml", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  FAIL("no InputError for:\n" << text);
  return {};
}

// 1-based line of the first line of `text` that contains `needle`.
int line_of(const std::string& text, const std::string& needle) {
  int line = 1;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = text.find('\n', start);
    const std::string l = text.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (l.find(needle) != std::string::npos) return line;
    if (end == std::string::npos) break;
    start = end + 1;
    ++line;
  }
  return -1;
}

struct TempDir {
  std::filesystem::path path;
  TempDir() {
    static int counter = 0;
    path = std::filesystem::temp_directory_path() /
           ("truss_scene_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const auto p = path / name;
    std::ofstream(p) << text;
    return p.string();
  }
};

const std::string kFull = R"(# every key, none at its default
[mast]
n_bays = 12
strut_length_m = 0.2
strut_mass_kg = 0.11
strut_inertia_kg_m2 = 0.0004
frame_side_m = 0.4
frame_mass_kg = 0.6
diagonal_stiffness_N_per_m = 25   # an integer for a float key
diagonal_free_length_m = 0.5
tip_mass_kg = 1.5

[rail]
x_m = 0.09
y_m = 0.16
beta_deg = 25.5

[drive]
mode = "motor"
speed_m_per_s = 0.05
screw_lead_m = 0.02
torque_Nm = 0.03
stall_torque_Nm = 0.04
no_load_speed_rad_per_s = 80.0
gear_ratio = 5
gear_efficiency = 0.9
screw_efficiency = 0.4
screw_back_efficiency = 0.2
friction_torque_Nm = 0.001
detent_torque_Nm = 0.0002
hysteresis_torque_Nm = 0.0001
harness_torque_Nm = 0.0003
motor_derating = 0.8

[stack]
mode = "free"
contacts = true
contact_law = "plastic"
start = "rest"

[panels]
count = 4
length_m = 0.6
mass_kg = 0.3
tip_height_m = 0.4

[run]
direction = "retract"
output_step_s = 0.02
rtol = 1e-6
atol = 1e-9
integrator = "cvode"
max_steps = 5000000000
max_wall_time_s = 30

[motorisation]
factor = 2.5
spring_factor = 1.3
inertia_factor = 1.4
friction_factor = 1.5
detent_factor = 1.2
hysteresis_factor = 1.6
harness_factor = 1.7
)";

}  // namespace

// kFull sets keys to values that a given version of validate() may refuse (stack.mode = "free"),
// so the tests of the key mapping parse without validation; validate() has its own tests below.
TEST_CASE("a full scene file sets every key", "[scene]") {
  const SceneOptions s = truss::io::parse_scene_text_unvalidated(kFull, "full.toml", {});
  CHECK(s.mast.n_bays == 12);
  CHECK(s.mast.strut_length_m == 0.2);
  CHECK(s.mast.strut_mass_kg == 0.11);
  REQUIRE(s.mast.strut_inertia_kg_m2.has_value());
  CHECK(*s.mast.strut_inertia_kg_m2 == 0.0004);
  CHECK(s.mast.frame_side_m == 0.4);
  CHECK(s.mast.frame_mass_kg == 0.6);
  CHECK(s.mast.diagonal_stiffness_N_per_m == 25.0);
  CHECK(s.mast.diagonal_free_length_m == 0.5);
  REQUIRE(s.mast.tip_mass_kg.has_value());
  CHECK(*s.mast.tip_mass_kg == 1.5);
  CHECK(s.rail.x_m == 0.09);
  CHECK(s.rail.y_m == 0.16);
  CHECK(s.rail.beta_deg == 25.5);
  CHECK(s.drive.mode == DriveMode::motor);
  CHECK(s.drive.speed_m_per_s == 0.05);
  CHECK(s.drive.screw_lead_m == 0.02);
  CHECK(s.drive.torque_Nm == 0.03);
  CHECK(s.drive.stall_torque_Nm == 0.04);
  CHECK(s.drive.no_load_speed_rad_per_s == 80.0);
  CHECK(s.drive.gear_ratio == 5.0);
  CHECK(s.drive.gear_efficiency == 0.9);
  CHECK(s.drive.screw_efficiency == 0.4);
  CHECK(s.drive.screw_back_efficiency == 0.2);
  CHECK(s.drive.friction_torque_Nm == 0.001);
  CHECK(s.drive.detent_torque_Nm == 0.0002);
  CHECK(s.drive.hysteresis_torque_Nm == 0.0001);
  CHECK(s.drive.harness_torque_Nm == 0.0003);
  CHECK(s.drive.motor_derating == 0.8);
  CHECK(s.motorisation.factor == 2.5);
  CHECK(s.motorisation.spring_factor == 1.3);
  CHECK(s.motorisation.inertia_factor == 1.4);
  CHECK(s.motorisation.friction_factor == 1.5);
  CHECK(s.motorisation.detent_factor == 1.2);
  CHECK(s.motorisation.hysteresis_factor == 1.6);
  CHECK(s.motorisation.harness_factor == 1.7);
  CHECK(s.stack.mode == StackMode::free);
  CHECK(s.stack.contacts == truss::sim::StackContacts::on);
  CHECK(s.stack.contact_law == truss::sim::ContactLaw::plastic);
  CHECK(s.stack.start == truss::sim::StackStart::rest);
  CHECK(s.panels.count == 4);
  CHECK(s.panels.length_m == 0.6);
  CHECK(s.panels.mass_kg == 0.3);
  REQUIRE(s.panels.tip_height_m.has_value());
  CHECK(*s.panels.tip_height_m == 0.4);
  CHECK(s.run.direction == Direction::retract);
  CHECK(s.run.output_step_s == 0.02);
  CHECK(s.run.rtol == 1e-6);
  CHECK(s.run.atol == 1e-9);
  CHECK(s.run.integrator == IntegratorKind::cvode);
  CHECK(s.run.max_steps == 5'000'000'000L);
  CHECK(s.run.max_wall_time_s == 30.0);
}

TEST_CASE("missing keys keep the defaults of scene.hpp", "[scene]") {
  const SceneOptions def;
  SECTION("empty file") {
    const SceneOptions s = parse_scene_text("", "empty.toml", {});
    CHECK(resolved_scene_toml(s) == resolved_scene_toml(def));
    CHECK(s.mast.n_bays == def.mast.n_bays);
    CHECK(s.rail.beta_deg == def.rail.beta_deg);
    CHECK(!s.mast.strut_inertia_kg_m2.has_value());
    CHECK(!s.mast.tip_mass_kg.has_value());
    CHECK(!s.panels.tip_height_m.has_value());
  }
  SECTION("one key set, the others untouched") {
    const SceneOptions s = parse_scene_text("[rail]\nbeta_deg = 30\n", "one.toml", {});
    CHECK(s.rail.beta_deg == 30.0);
    SceneOptions expected;
    expected.rail.beta_deg = 30.0;
    CHECK(resolved_scene_toml(s) == resolved_scene_toml(expected));
  }
  SECTION("inline tables and dotted keys are the same tables") {
    const SceneOptions s =
        parse_scene_text("rail = { beta_deg = 31 }\nmast.n_bays = 7\n", "inline.toml", {});
    CHECK(s.rail.beta_deg == 31.0);
    CHECK(s.mast.n_bays == 7);
  }
}

TEST_CASE("the repository's Table 1 scene is the defaults with histories on", "[scene]") {
  const SceneOptions s =
      parse_scene_file(std::string(TRUSS_SOURCE_DIR) + "/campaigns/scenes/table1.toml", {});
  SceneOptions expected;
  expected.run.output_step_s = 0.01;
  CHECK(resolved_scene_toml(s) == resolved_scene_toml(expected));
  CHECK(s.drive.mode == DriveMode::velocity);
  CHECK(s.stack.mode == StackMode::held);
  CHECK(s.panels.count == 0);
  CHECK(s.run.direction == Direction::deploy);
}

TEST_CASE("the drive train refuses what it cannot model, naming the key and line", "[scene][errors]") {
  const std::string locked = parse_error("[drive]\nscrew_efficiency = 0.3\nscrew_back_efficiency = -0.1\n");
  CHECK_THAT(locked, StartsWith("error: scene.toml:3: drive.screw_back_efficiency"));
  CHECK_THAT(locked, Contains("self-locking"));
  CHECK_THAT(parse_error("[drive]\ngear_efficiency = 1.05\n"), Contains("drive.gear_efficiency: must lie in (0, 1]"));
  CHECK_THAT(parse_error("[drive]\nharness_torque_Nm = -0.001\n"), Contains("drive.harness_torque_Nm: must lie in [0, "));
  CHECK_THAT(parse_error("[motorisation]\nfactor = 0\n"), Contains("motorisation.factor: must lie in (0, "));
}

TEST_CASE("unknown keys and tables are named with their line and a suggestion", "[scene][errors]") {
  SECTION("unknown key in a known table") {
    const std::string text = "[mast]\nn_bays = 3\nn_bay = 4\n";
    const std::string msg = parse_error(text);
    CHECK_THAT(msg, StartsWith("error: scene.toml:3: "));
    CHECK_THAT(msg, Contains("unknown key 'mast.n_bay'"));
    CHECK_THAT(msg, Contains("did you mean 'mast.n_bays'?"));
  }
  SECTION("a key of another table") {
    const std::string msg = parse_error("[rail]\n\nspeed_m_per_s = 0.2\n");
    CHECK_THAT(msg, StartsWith("error: scene.toml:3: "));
    CHECK_THAT(msg, Contains("'rail.speed_m_per_s'"));
    CHECK_THAT(msg, Contains("did you mean 'drive.speed_m_per_s'?"));
  }
  SECTION("nothing close: the known keys are listed") {
    const std::string msg = parse_error("[stack]\nzzzzzzzz = 1\n");
    CHECK_THAT(msg, Contains("unknown key 'stack.zzzzzzzz'"));
    CHECK_THAT(msg, Contains("mode"));
    CHECK_THAT(msg, !Contains("did you mean"));
  }
  SECTION("unknown table") {
    const std::string msg = parse_error("[mast]\nn_bays = 3\n\n[masts]\nn_bays = 4\n");
    CHECK_THAT(msg, StartsWith("error: scene.toml:4: "));
    CHECK_THAT(msg, Contains("unknown table [masts]"));
    CHECK_THAT(msg, Contains("did you mean [mast]?"));
  }
  SECTION("key at the top level") {
    const std::string msg = parse_error("\nbeta_deg = 30\n");
    CHECK_THAT(msg, StartsWith("error: scene.toml:2: "));
    CHECK_THAT(msg, Contains("'beta_deg'"));
    CHECK_THAT(msg, Contains("did you mean 'rail.beta_deg'?"));
  }
  SECTION("sub-table of a known table") {
    const std::string msg = parse_error("[mast.extra]\nq = 1\n");
    CHECK_THAT(msg, Contains("unknown key 'mast.extra'"));
  }
  SECTION("several errors are all reported, in file order") {
    const std::string msg = parse_error("[run]\nrtoll = 1e-6\n[mast]\nn_bayz = 3\n");
    const auto a = msg.find("scene.toml:2:"), b = msg.find("scene.toml:4:");
    REQUIRE(a != std::string::npos);
    REQUIRE(b != std::string::npos);
    CHECK(a < b);
  }
}

TEST_CASE("wrong value types name the key, the expected type and the line", "[scene][errors]") {
  SECTION("float for an int") {
    const std::string msg = parse_error("[mast]\nn_bays = 12.5\n");
    CHECK_THAT(msg, StartsWith("error: scene.toml:2: mast.n_bays: "));
    CHECK_THAT(msg, Contains("expected an integer"));
    CHECK_THAT(msg, Contains("12.5"));
  }
  SECTION("string for a float") {
    const std::string msg = parse_error("[rail]\nx_m = 0.08\ny_m = \"high\"\n");
    CHECK_THAT(msg, StartsWith("error: scene.toml:3: rail.y_m: "));
    CHECK_THAT(msg, Contains("expected a number"));
  }
  SECTION("boolean for a float") {
    CHECK_THAT(parse_error("[run]\nrtol = true\n"), Contains("run.rtol: expected a number"));
  }
  SECTION("integer for an enumeration") {
    const std::string msg = parse_error("[run]\nintegrator = 3\n");
    CHECK_THAT(msg, StartsWith("error: scene.toml:2: run.integrator: "));
    CHECK_THAT(msg, Contains("expected a string"));
  }
  SECTION("a value where a table belongs") {
    const std::string msg = parse_error("mast = 3\n");
    CHECK_THAT(msg, StartsWith("error: scene.toml:1: mast: "));
    CHECK_THAT(msg, Contains("expected a table"));
  }
  SECTION("integer out of the range of the field") {
    CHECK_THAT(parse_error("[mast]\nn_bays = 99999999999\n"),
               Contains("mast.n_bays: integer 99999999999 is out of range"));
  }
}

TEST_CASE("bad enumeration values list the allowed values", "[scene][errors]") {
  const std::string msg = parse_error("[drive]\nmode = \"motr\"\n");
  CHECK_THAT(msg, StartsWith("error: scene.toml:2: drive.mode: "));
  CHECK_THAT(msg, Contains("\"motr\""));
  CHECK_THAT(msg, Contains("\"velocity\", \"torque\", \"motor\""));
  CHECK_THAT(parse_error("[stack]\nmode = \"loose\"\n"), Contains("\"held\", \"free\""));
  CHECK_THAT(parse_error("[run]\ndirection = \"up\"\n"), Contains("\"deploy\", \"retract\""));
  CHECK_THAT(parse_error("[run]\nintegrator = \"rk4\"\n"), Contains("\"dopri54\", \"cvode\""));
  // Stack contacts: TOML booleans only; the contact law by name.
  CHECK_THAT(parse_error("[stack]\nmode = \"free\"\ncontacts = \"yes\"\n"), StartsWith("error: scene.toml:3: stack.contacts: expected true or false"));
  CHECK_THAT(parse_error("[stack]\nmode = \"free\"\ncontacts = true\ncontact_law = \"elastic\"\n"),
             StartsWith("error: scene.toml:4: stack.contact_law: unknown value \"elastic\""));
  // Contacts on a held stack: validate() names the key and its line.
  CHECK_THAT(parse_error("[stack]\nmode = \"held\"\n\ncontacts = true\n"), StartsWith("error: scene.toml:4: stack.contacts: "));
  // The free frames' start: by name; "rest" on a held stack names the key and its line.
  CHECK_THAT(parse_error("[stack]\nmode = \"free\"\nstart = \"still\"\n"),
             StartsWith("error: scene.toml:3: stack.start: unknown value \"still\""));
  CHECK_THAT(parse_error("[stack]\nmode = \"held\"\nstart = \"rest\"\n"), StartsWith("error: scene.toml:3: stack.start: "));
  // Enumerations are case-sensitive, like TOML keys.
  CHECK_THAT(parse_error("[drive]\nmode = \"Motor\"\n"), Contains("drive.mode"));
}

TEST_CASE("TOML syntax errors give file:line:col and toml++'s description", "[scene][errors]") {
  const std::string msg = parse_error("[mast]\nn_bays = 3\nstrut_length_m = = 0.2\n");
  CHECK_THAT(msg, StartsWith("error: scene.toml:3:"));
  CHECK_THAT(msg, Contains("TOML syntax error"));
  const std::string dup = parse_error("[mast]\nn_bays = 3\nn_bays = 4\n");
  CHECK_THAT(dup, StartsWith("error: scene.toml:3:"));
  CHECK_THAT(dup, Contains("n_bays"));
}

TEST_CASE("unreadable scene files", "[scene][errors]") {
  TempDir dir;
  const std::string missing = (dir.path / "nope.toml").string();
  try {
    parse_scene_file(missing, {});
    FAIL("no InputError for a missing file");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), StartsWith("error: " + missing + ": cannot read scene file"));
    CHECK_THAT(e.what(), Contains("No such file"));
  }
  CHECK_THROWS_AS(parse_scene_file(dir.path.string(), {}), InputError);  // a directory
  // A file that exists is read, and errors in it carry its path.
  const std::string bad = dir.write("bad.toml", "[mast]\nn_bays = \"x\"\n");
  try {
    parse_scene_file(bad, {});
    FAIL("no InputError for a bad file");
  } catch (const InputError& e) {
    CHECK_THAT(e.what(), StartsWith("error: " + bad + ":2: mast.n_bays"));
  }
}

TEST_CASE("--set overrides", "[scene][set]") {
  const std::string base = "[mast]\nn_bays = 5\n";
  SECTION("numbers, bare words and quoted strings; overrides win over the file, the last wins") {
    const SceneOptions s = parse_scene_text(
        base, "scene.toml",
        {"mast.n_bays=12", "rail.beta_deg=25", "drive.mode=motor", "run.direction=\"retract\"",
         "mast.tip_mass_kg = 2.5", "run.rtol=1e-7", "run.rtol=2e-7"});
    CHECK(s.mast.n_bays == 12);
    CHECK(s.rail.beta_deg == 25.0);
    CHECK(s.drive.mode == DriveMode::motor);
    CHECK(s.run.direction == Direction::retract);
    REQUIRE(s.mast.tip_mass_kg.has_value());
    CHECK(*s.mast.tip_mass_kg == 2.5);
    CHECK(s.run.rtol == 2e-7);
  }
  SECTION("unknown key") {
    const std::string msg = parse_error(base, {"mast.n_bay=12"});
    CHECK_THAT(msg, StartsWith("error: --set mast.n_bay=12: "));
    CHECK_THAT(msg, Contains("unknown key 'mast.n_bay'"));
    CHECK_THAT(msg, Contains("did you mean 'mast.n_bays'?"));
  }
  SECTION("unknown table, missing table, missing '='") {
    CHECK_THAT(parse_error(base, {"masts.n_bays=1"}), Contains("unknown table [masts]"));
    CHECK_THAT(parse_error(base, {"n_bays=1"}), Contains("did you mean 'mast.n_bays'?"));
    CHECK_THAT(parse_error(base, {"mast.n_bays"}), StartsWith("error: --set mast.n_bays: "));
  }
  SECTION("bad values") {
    const std::string msg = parse_error(base, {"mast.n_bays=twelve"});
    CHECK_THAT(msg, StartsWith("error: --set mast.n_bays=twelve: mast.n_bays: "));
    CHECK_THAT(msg, Contains("expected an integer"));
    CHECK_THAT(parse_error(base, {"mast.n_bays=12.5"}), Contains("expected an integer"));
    CHECK_THAT(parse_error(base, {"rail.beta_deg=steep"}), Contains("expected a number"));
    CHECK_THAT(parse_error(base, {"drive.mode=motr"}), Contains("\"velocity\", \"torque\", \"motor\""));
    CHECK_THAT(parse_error(base, {"run.rtol="}), Contains("missing value"));
  }
  SECTION("the file's line is not blamed for an override") {
    const std::string msg = parse_error(base, {"mast.n_bays=x"});
    CHECK_THAT(msg, !Contains("scene.toml:"));
  }
}

TEST_CASE("values that validate() rejects name the key and its line", "[scene][validate]") {
  SECTION("in the file") {
    const std::string text = "[mast]\nn_bays = 3\n\n[rail]\nx_m = 0.08\n# steep\nbeta_deg = 95\n";
    const std::string msg = parse_error(text);
    CHECK_THAT(msg, StartsWith("error: scene.toml:" + std::to_string(line_of(text, "beta_deg")) +
                               ": rail.beta_deg: "));
    CHECK_THAT(msg, Contains("95"));
  }
  SECTION("the message is validate()'s own") {
    SceneOptions bad;
    bad.rail.beta_deg = 95;
    const std::string why = bad.validate();
    REQUIRE(!why.empty());
    CHECK_THAT(parse_error("[rail]\nbeta_deg = 95\n"), Contains(why));
  }
  SECTION("in an override") {
    const std::string msg = parse_error("[rail]\nbeta_deg = 30\n", {"rail.beta_deg=95"});
    CHECK_THAT(msg, StartsWith("error: scene.toml: rail.beta_deg: "));
    CHECK_THAT(msg, Contains("--set rail.beta_deg=95"));
  }
  SECTION("an override can repair the file") {
    const SceneOptions s = parse_scene_text("[rail]\nbeta_deg = 95\n", "scene.toml", {"rail.beta_deg=30"});
    CHECK(s.rail.beta_deg == 30.0);
  }
}

TEST_CASE("resolved_scene_toml writes every key and reads back to the same options", "[scene][resolved]") {
  SECTION("defaults: optional keys unset, and unset after the round trip") {
    const SceneOptions def;
    const std::string text = resolved_scene_toml(def);
    for (const auto& key : truss::io::known_scene_keys()) {
      const std::string name = key.substr(key.find('.') + 1);
      INFO(key);
      CHECK(line_of(text, name) > 0);
    }
    const SceneOptions back = parse_scene_text(text, "resolved.toml", {});
    CHECK(!back.mast.strut_inertia_kg_m2.has_value());
    CHECK(!back.mast.tip_mass_kg.has_value());
    CHECK(!back.panels.tip_height_m.has_value());
    CHECK(resolved_scene_toml(back) == text);
  }
  SECTION("awkward doubles and every key set") {
    SceneOptions s = truss::io::parse_scene_text_unvalidated(kFull, "full.toml", {});
    s.rail.beta_deg = 0.1 + 0.2;  // 0.30000000000000004
    s.run.atol = 1e-300;
    s.drive.speed_m_per_s = 1.0 / 3.0;
    s.mast.diagonal_stiffness_N_per_m = 20.0;  // integral value, must stay a float
    s.run.max_wall_time_s = 1e300;
    const std::string text = resolved_scene_toml(s);
    CHECK(line_of(text, "diagonal_stiffness_N_per_m = 20.0") > 0);
    const SceneOptions back = truss::io::parse_scene_text_unvalidated(text, "resolved.toml", {});
    CHECK(back.rail.beta_deg == 0.1 + 0.2);
    CHECK(back.run.atol == 1e-300);
    CHECK(back.drive.speed_m_per_s == 1.0 / 3.0);
    CHECK(back.run.max_wall_time_s == 1e300);
    CHECK(back.drive.mode == DriveMode::motor);
    CHECK(back.stack.mode == StackMode::free);
    CHECK(back.stack.contacts == truss::sim::StackContacts::on);
    CHECK(line_of(text, "contacts = true") > 0);  // a TOML boolean, not a string
    CHECK(back.run.integrator == IntegratorKind::cvode);
    CHECK(back.run.max_steps == 5'000'000'000L);
    REQUIRE(back.panels.tip_height_m.has_value());
    CHECK(*back.panels.tip_height_m == 0.4);
    CHECK(resolved_scene_toml(back) == text);
  }
}

TEST_CASE("parse_scene_text_unvalidated checks everything but validate()", "[scene][validate]") {
  const std::string text = "[rail]\nbeta_deg = 95\n";
  CHECK(truss::io::parse_scene_text_unvalidated(text, "scene.toml", {}).rail.beta_deg == 95.0);
  CHECK_THROWS_AS(parse_scene_text(text, "scene.toml", {}), InputError);
  CHECK_THROWS_AS(truss::io::parse_scene_text_unvalidated("[rail]\nbeta = 3\n", "scene.toml", {}),
                  InputError);
  CHECK_THROWS_AS(truss::io::parse_scene_text_unvalidated("[mast]\nn_bays = 1.5\n", "scene.toml", {}),
                  InputError);
  CHECK_THROWS_AS(truss::io::parse_scene_text_unvalidated("", "scene.toml", {"drive.mode=fast"}),
                  InputError);
}
