// truss_deploy.Scene and truss_deploy.scene_keys(): scenes read and checked exactly as truss-sim
// reads them (io/scene_toml), keys, units and ranges from the one scene key table (sim/scene_keys).
#include <cerrno>
#include <filesystem>
#include <string_view>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sim/scene_keys.hpp"

namespace truss::py {

namespace {

constexpr const char* kTable1Source = "Scene.table1()";

bool is_yes_no(const sim::SceneKey& k) {
  return k.kind == sim::KeyKind::enumeration && k.allowed.size() == 2 && k.allowed[0] == "false" &&
         k.allowed[1] == "true";
}

// The value of one key of the scene in Python: float, int, str (enumerations), bool (yes/no
// keys), None (an optional key left unset: its default is computed from other keys).
pyb::object key_to_py(const sim::SceneKey& k, const sim::SceneOptions& s) {
  switch (k.kind) {
    case sim::KeyKind::real:
      return pyb::float_(k.get_real(s));
    case sim::KeyKind::opt_real: {
      const auto v = k.get_opt(s);
      return v ? pyb::object(pyb::float_(*v)) : pyb::object(pyb::none());
    }
    case sim::KeyKind::integer:
      return pyb::int_(k.get_int(s));
    case sim::KeyKind::enumeration: {
      const std::size_t i = k.get_enum(s);
      if (is_yes_no(k)) return pyb::bool_(i == 1);
      return pyb::str(std::string(k.allowed.at(i)));
    }
  }
  throw std::logic_error("unknown key kind");
}

const sim::SceneKey& find_key_or_raise(const std::string& key) {
  const sim::SceneKey* k = sim::find_scene_key(key);
  if (!k) throw pyb::key_error(fmt::format("unknown scene key '{}' (truss_deploy.scene_keys() lists them)", key));
  return *k;
}

const char* kind_name(sim::KeyKind k) {
  switch (k) {
    case sim::KeyKind::real:
      return "real";
    case sim::KeyKind::opt_real:
      return "optional real";
    case sim::KeyKind::integer:
      return "integer";
    case sim::KeyKind::enumeration:
      return "enumeration";
  }
  return "?";
}

const char* scope_name(sim::KeyScope s) {
  switch (s) {
    case sim::KeyScope::fixed:
      return "fixed";
    case sim::KeyScope::run:
      return "run";
    case sim::KeyScope::bay:
      return "bay";
    case sim::KeyScope::frame:
      return "frame";
  }
  return "?";
}

// One dict per key of the table, in its order.
pyb::list scene_key_rows() {
  pyb::list rows;
  for (const auto& k : sim::scene_keys()) {
    pyb::dict d;
    d["key"] = k.dotted();
    d["kind"] = kind_name(k.kind);
    d["unit"] = std::string(k.unit);
    d["comment"] = std::string(k.comment);
    d["dispersible_per"] = scope_name(k.scope);
    pyb::list allowed;
    for (auto a : k.allowed) allowed.append(std::string(a));
    d["allowed"] = allowed;
    const bool numeric = k.kind != sim::KeyKind::enumeration;
    d["hard_range"] = numeric ? pyb::object(pyb::str(k.hard.text())) : pyb::object(pyb::none());
    d["typical_range"] = numeric ? pyb::object(pyb::str(k.typical.text())) : pyb::object(pyb::none());
    rows.append(d);
  }
  return rows;
}

// The settings of with_(mapping, **kwargs), in the order given.
std::vector<io::SceneSetting> settings_of(const pyb::args& args, const pyb::kwargs& kwargs) {
  std::vector<io::SceneSetting> out;
  if (args.size() > 1) throw pyb::type_error("with_() takes at most one mapping besides the keyword arguments");
  auto add = [&](const pyb::dict& d) {
    for (auto [k, v] : d) out.push_back(python_setting(pyb::str(k), v));
  };
  if (args.size() == 1) add(pyb::dict(args[0]));
  add(kwargs);
  return out;
}

std::string scene_repr(const Scene& s) {
  std::string r = s.source == kTable1Source
                      ? "Scene.table1()"
                      : fmt::format("Scene.from_toml({})", pyb::repr(pyb::str(s.source)).cast<std::string>());
  if (s.settings.empty()) return r;
  std::string args;
  for (const auto& set : s.settings)
    args += fmt::format("{}{}", args.empty() ? "" : ", ", pyb::repr(pyb::str(set.assignment)).cast<std::string>());
  return fmt::format("{}.with_settings([{}])", r, args);
}

}  // namespace

Scene make_scene(std::string text, std::string source, std::vector<io::SceneSetting> settings) {
  std::vector<std::string> warnings;
  Scene s{std::move(text), std::move(source), std::move(settings), {}};
  try {
    s.options = io::parse_scene_text_with(s.text, s.source, s.settings, &warnings);
  } catch (const io::InputError& e) {
    throw pyb::value_error(python_message(e.what()));
  }
  for (const auto& w : warnings)  // -W error: raised
    if (PyErr_WarnEx(PyExc_UserWarning, python_message(w).c_str(), 1) != 0) throw pyb::error_already_set();
  return s;
}

std::string python_message(const std::string& message) {
  std::string out;
  std::size_t start = 0;
  while (start <= message.size()) {
    std::size_t end = message.find('\n', start);
    if (end == std::string::npos) end = message.size();
    std::string_view line(message.data() + start, end - start);
    for (std::string_view prefix : {"error: ", "warning: "})
      if (line.starts_with(prefix)) line.remove_prefix(prefix.size());
    out.append(line);
    if (end < message.size()) out += '\n';
    start = end + 1;
  }
  return out;
}

io::SceneSetting python_setting(const std::string& key, pyb::handle value) {
  std::string text = setting_text(key, value);
  return {std::move(text), fmt::format("{}: {}", pyb::repr(pyb::str(key)).cast<std::string>(),
                                       pyb::repr(value).cast<std::string>())};
}

std::string setting_text(const std::string& key, pyb::handle value) {
  PyObject* p = value.ptr();
  const std::string type_name = pyb::str(pyb::type::of(value).attr("__name__"));
  // An array (numpy's, of any shape but ()) is not one value: numpy scalars and 0-d arrays are.
  if (PyObject_HasAttrString(p, "shape") && pyb::len(value.attr("shape")) != 0)
    throw pyb::type_error(fmt::format("{}: expected a number, a bool or a string, got {} of shape {}", key, type_name,
                                      pyb::repr(value.attr("shape")).cast<std::string>()));
  if (PyBool_Check(p) || type_name == "bool_") return key + "=" + (PyObject_IsTrue(p) ? "true" : "false");
  if (PyUnicode_Check(p)) return key + "=" + value.cast<std::string>();
  if (PyFloat_Check(p)) return key + "=" + io::toml_double(PyFloat_AsDouble(p));
  if (PyIndex_Check(p)) {
    PyObject* index = PyNumber_Index(p);
    if (index == nullptr) throw pyb::error_already_set();
    return key + "=" + pyb::str(pyb::reinterpret_steal<pyb::object>(index)).cast<std::string>();
  }
  if (PyNumber_Check(p) && PyObject_HasAttrString(p, "__float__")) {  // numpy.float32 and the like
    const double v = PyFloat_AsDouble(p);
    if (v == -1.0 && PyErr_Occurred()) throw pyb::error_already_set();
    return key + "=" + io::toml_double(v);
  }
  throw pyb::type_error(fmt::format("{}: expected a number, a bool or a string, got {}", key, type_name));
}

void bind_scene(pyb::module_& m) {
  pyb::class_<Scene>(m, "Scene", R"(A scene: a mast, its rail, drive, stack, panels and run options, read and
checked as truss-sim reads them. Immutable: with_() returns a new scene.)")
      .def_static(
          "from_toml",
          [](const std::string& path) {
            std::error_code ec;
            if (!std::filesystem::exists(path, ec)) {  // Python's own error for a missing file
              errno = ENOENT;
              PyErr_SetFromErrnoWithFilename(PyExc_FileNotFoundError, path.c_str());
              throw pyb::error_already_set();
            }
            try {
              return make_scene(io::read_input_file(path, "scene file"), path, {});
            } catch (const io::InputError& e) {
              throw pyb::value_error(python_message(e.what()));
            }
          },
          pyb::arg("path"),
          "A scene file (TOML), e.g. campaigns/scenes/table1.toml; FileNotFoundError when it does not exist, "
          "ValueError (truss-sim's message) when it is not a valid scene.")
      .def_static(
          "table1", [] { return make_scene("", kTable1Source, {}); },
          "The paper's Table 1 mast with every default (docs/model.md §4), no time histories.")
      .def(
          "with_",
          [](const Scene& s, const pyb::args& args, const pyb::kwargs& kwargs) {
            auto settings = s.settings;
            for (auto& set : settings_of(args, kwargs)) settings.push_back(std::move(set));
            return make_scene(s.text, s.source, std::move(settings));
          },
          R"(A new scene with keys set, as truss-sim's --set: scene.with_({"mast.n_bays": 12}) or
scene.with_(**{"drive.mode": "motor"}). Unknown keys and bad values raise ValueError with truss-sim's message.)")
      .def(
          "with_settings",
          [](const Scene& s, const std::vector<std::string>& assignments) {
            auto settings = s.settings;
            for (const auto& a : assignments) settings.push_back({a, {}});
            return make_scene(s.text, s.source, std::move(settings));
          },
          pyb::arg("assignments"), "A new scene with \"table.key=value\" settings, exactly as given to --set.")
      .def(
          "__getitem__",
          [](const Scene& s, const std::string& key) { return key_to_py(find_key_or_raise(key), s.options); },
          "The resolved value of a key (\"mast.n_bays\"); None for an optional key left unset.")
      .def(
          "to_dict",
          [](const Scene& s) {
            pyb::dict d;
            for (const auto& k : sim::scene_keys()) d[pyb::str(k.dotted())] = key_to_py(k, s.options);
            return d;
          },
          "Every key with its value, in the order of the key table.")
      .def(
          "to_toml", [](const Scene& s) { return io::resolved_scene_toml(s.options); },
          "The resolved scene as TOML (every key, defaults included); reads back to the same scene.")
      .def_property_readonly("source", [](const Scene& s) { return s.source; })
      .def_property_readonly("settings",
                             [](const Scene& s) {
                               std::vector<std::string> v;
                               for (const auto& set : s.settings) v.push_back(set.assignment);
                               return v;
                             })
      .def("__repr__", &scene_repr);
  m.def("scene_keys", &scene_key_rows,
        "The scene key table: one dict per key (key, kind, unit, comment, dispersible_per, allowed, hard_range, "
        "typical_range).");
}

}  // namespace truss::py
