// The Python module truss_deploy._core (pybind11): scenes through the scene key table and the TOML
// reader (io/scene_toml), runs through sim::simulate, results through the JSON summary's field
// tables (io/json_summary). The pure-Python part (truss_deploy/__init__.py) builds the pandas
// tables of simulate_many. Bad input raises ValueError with the message truss-sim prints.
#pragma once
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

#include "io/json_summary.hpp"
#include "io/scene_toml.hpp"
#include "sim/result.hpp"
#include "sim/scene.hpp"

namespace truss::py {

namespace pyb = pybind11;

// A parsed and validated scene: the TOML text it was read from, the name messages give it, the
// settings applied on top (as truss-sim's --set), and the options they resolve to.
struct Scene {
  std::string text;                        // "" for Scene.table1()
  std::string source;                      // the file path, or "Scene.table1()"
  std::vector<io::SceneSetting> settings;  // "table.key=value", in order
  sim::SceneOptions options;
};

// Parses text + settings as truss-sim does (io::parse_scene_text_with); io::InputError becomes
// ValueError with the same message, and each plausibility warning a Python UserWarning.
Scene make_scene(std::string text, std::string source, std::vector<io::SceneSetting> settings);

// "table.key=value" for a Python value, as a user would type it after truss-sim's --set: a bool
// as true/false, an integer as itself, a float so that it reads back exactly ("12.0", "1e-05"),
// a string as it is (a bare word is read as a string). TypeError for anything else.
std::string setting_text(const std::string& key, pyb::handle value);

// A key set from Python (with_(), simulate_many's overrides): its setting, whose messages name it
// as Python wrote it ('mast.n_bays': 12), not as a --set option.
io::SceneSetting python_setting(const std::string& key, pyb::handle value);

// An input error's or warning's message for Python: the command line's "error: " and "warning: "
// prefixes of its lines dropped.
std::string python_message(const std::string& message);

// A finished run and whether its histories were recorded.
struct Result {
  sim::RunResult run;
  bool histories = false;
};

void bind_scene(pyb::module_& m);
void bind_result(pyb::module_& m);
void bind_many(pyb::module_& m);

// A field value of the JSON summary's tables as a Python float, int or str.
pyb::object field_to_py(const io::FieldValue& v);

}  // namespace truss::py
