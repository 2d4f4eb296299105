// truss_deploy.simulate and truss_deploy.Result: one run through sim::simulate (the GIL released),
// its summary through the JSON summary's field tables (io/json_summary): every field truss-sim
// --json prints is an attribute of the same name, the bays a pandas DataFrame, the histories numpy
// arrays.
#include <fmt/format.h>
#include <pybind11/numpy.h>

#include <algorithm>

#include "bindings.hpp"
#include "sim/simulate.hpp"

namespace truss::py {

namespace {

template <class T>
pyb::array_t<T> to_array(const std::vector<T>& v) {
  return pyb::array_t<T>(static_cast<pyb::ssize_t>(v.size()), v.data());
}

// {field: unit} of one field table.
template <class Fields>
pyb::dict units_of(const Fields& fields) {
  pyb::dict d;
  for (const auto& f : fields) d[f.name] = f.units;
  return d;
}

// The bays as a pandas DataFrame: one row per bay, one column per BayResult field.
pyb::object bays_frame(const sim::RunResult& r) {
  pyb::dict cols;
  for (const auto& f : io::bay_result_fields()) {
    const bool is_int = std::holds_alternative<std::int64_t>(f.get(sim::BayResult{}));
    if (is_int) {
      pyb::array_t<std::int64_t> a(static_cast<pyb::ssize_t>(r.bays.size()));
      for (std::size_t i = 0; i < r.bays.size(); ++i) a.mutable_at(i) = std::get<std::int64_t>(f.get(r.bays[i]));
      cols[f.name] = a;
    } else {
      pyb::array_t<double> a(static_cast<pyb::ssize_t>(r.bays.size()));
      for (std::size_t i = 0; i < r.bays.size(); ++i) a.mutable_at(i) = std::get<double>(f.get(r.bays[i]));
      cols[f.name] = a;
    }
  }
  pyb::object df = pyb::module_::import("pandas").attr("DataFrame")(cols);
  df.attr("attrs")["units"] = units_of(io::bay_result_fields());
  return df;
}

// The time histories as {name: numpy array}; the free stack's frame heights as rows x frames.
pyb::object history_dict(const Result& res) {
  if (!res.histories) return pyb::none();
  const auto& h = res.run.history;
  pyb::dict d;
  for (const auto& f : io::history_fields()) {
    if (f.get_double)
      d[f.name] = to_array(*f.get_double(h));
    else
      d[f.name] = to_array(*f.get_int(h));
  }
  if (h.n_frames > 0) {
    const auto rows = static_cast<pyb::ssize_t>(h.frame_height_m.size() / static_cast<std::size_t>(h.n_frames));
    d["frame_height_m"] = to_array(h.frame_height_m).reshape({rows, static_cast<pyb::ssize_t>(h.n_frames)});
  }
  return d;
}

// The summary as truss-sim --json writes it (same keys, same order), NaN where the JSON has null.
pyb::dict result_dict(const sim::RunResult& r) {
  pyb::dict d;
  d["status"] = sim::to_string(r.status);
  d["message"] = r.message;
  for (const auto& f : io::run_result_fields()) d[f.name] = field_to_py(f.get(r));
  d["history_samples"] = r.history.size();
  pyb::list bays;
  for (const auto& b : r.bays) {
    pyb::dict bd;
    for (const auto& f : io::bay_result_fields()) bd[f.name] = field_to_py(f.get(b));
    bays.append(bd);
  }
  d["bays"] = bays;
  return d;
}

std::string result_repr(const sim::RunResult& r) {
  return fmt::format("<Result {} {} {}: {}/{} bays, deploy_time_s={}, peak_drive_force_N={}{}>",
                     sim::to_string(r.status), r.drive_mode, r.direction, r.bays_completed, r.n_bays, r.deploy_time_s,
                     r.peak_drive_force_N, r.message.empty() ? "" : ", message=" + r.message);
}

Result simulate_scene(const Scene& scene, bool histories) {
  sim::SceneOptions o = scene.options;
  if (!histories) {
    o.run.output_step_s = 0.0;  // not asked for: not computed
  } else if (!(o.run.output_step_s > 0.0)) {
    throw pyb::value_error(
        fmt::format("histories=True: {} has run.output_step_s = 0 (no histories); give a step, e.g. "
                    "scene.with_(**{{\"run.output_step_s\": 0.01}})",
                    scene.source));
  }
  Result res;
  res.histories = histories;
  {
    pyb::gil_scoped_release nogil;
    res.run = sim::simulate(o);
  }
  // truss-sim's exit 2 (simulate's own checks beyond the parser's; not reached by a parsed scene).
  if (res.run.status == sim::RunStatus::invalid_input)
    throw pyb::value_error(fmt::format("{}: {}", scene.source, res.run.message));
  return res;
}

}  // namespace

pyb::object field_to_py(const io::FieldValue& v) {
  if (const auto* d = std::get_if<double>(&v)) return pyb::float_(*d);
  if (const auto* i = std::get_if<std::int64_t>(&v)) return pyb::int_(*i);
  return pyb::str(std::get<std::string>(v));
}

void bind_result(pyb::module_& m) {
  // Members named as the C++ enumerators (step_limit); str() is the name truss-sim --json, the HDF5
  // files and the DataFrames use ("step limit").
  pyb::enum_<sim::RunStatus> status(m, "RunStatus",
                                    "How a run ended (ok, or the physical or numerical reason it stopped).");
  for (int i = 0; i < sim::kRunStatusCount; ++i) {
    const auto s = static_cast<sim::RunStatus>(i);
    std::string id = sim::to_string(s);
    std::replace_if(
        id.begin(), id.end(), [](char c) { return c == ' ' || c == '-'; }, '_');
    status.value(id.c_str(), s);
  }
  // Replaces (no sibling: a .def would only add an overload behind pybind11's own __str__).
  status.attr("__str__") = pyb::cpp_function([](sim::RunStatus s) { return sim::to_string(s); }, pyb::name("__str__"),
                                             pyb::is_method(status));

  pyb::class_<Result> cls(m, "Result", R"(One run's summary: every field of truss-sim --json as an attribute of the
same name (units in the names), status a RunStatus, bays a pandas DataFrame, history numpy arrays.)");
  cls.def_property_readonly("status", [](const Result& r) { return r.run.status; })
      .def_property_readonly("message", [](const Result& r) { return r.run.message; })
      .def_property_readonly("history_samples", [](const Result& r) { return r.run.history.size(); })
      .def_property_readonly(
          "bays", [](const Result& r) { return bays_frame(r.run); },
          "One row per bay (bay, entry_time_s, lock_time_s, ...); units in df.attrs['units'].")
      .def_property_readonly("history", &history_dict,
                             "{name: numpy array} of the time histories (simulate(..., histories=True)), else None.")
      .def(
          "to_dict", [](const Result& r) { return result_dict(r.run); },
          "The summary as truss-sim --json writes it (same keys and order; NaN for null).")
      .def("__repr__", [](const Result& r) { return result_repr(r.run); });
  for (const auto& f : io::run_result_fields())
    cls.def_property_readonly(f.name, [get = f.get](const Result& r) { return field_to_py(get(r.run)); });

  pyb::dict units;
  for (const auto& f : io::run_result_fields()) units[f.name] = f.units;
  units["history_samples"] = "1";
  m.attr("run_units") = units;
  m.attr("bay_units") = units_of(io::bay_result_fields());
  m.attr("history_units") = units_of(io::history_fields());

  m.def("simulate", &simulate_scene, pyb::arg("scene"), pyb::arg("histories") = false,
        R"(Runs the scene (the GIL released) and returns its Result. histories=True records the time histories at
the scene's run.output_step_s; otherwise none are computed. A run that fails physically is a Result with
its status, not an exception.)");
}

}  // namespace truss::py
