// truss_deploy._core.simulate_many_*: many runs on parallel threads with the GIL released, their
// summaries gathered into columns (one per field of the JSON summary's tables), one row per run.
// The pure-Python simulate_many (truss_deploy/__init__.py) turns the columns into a DataFrame.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>
#include <variant>

#include "bindings.hpp"
#include "sim/simulate.hpp"

namespace truss::py {

namespace {

using Column = std::variant<std::vector<double>, std::vector<std::int64_t>, std::vector<std::string>>;

// What the workers fill: one slot per run in every column (each run writes its own slots only).
struct Outcome {
  std::vector<std::int64_t> status;
  std::vector<std::string> message;
  std::vector<Column> fields;                     // io::run_result_fields(), in order
  std::vector<std::vector<sim::BayResult>> bays;  // empty unless the bays were asked for
  std::vector<std::string> warning;               // first plausibility warning of each run ("" if none)

  Outcome(std::size_t n, bool with_bays) : status(n), message(n), bays(with_bays ? n : 0), warning(n) {
    for (const auto& f : io::run_result_fields()) {
      const io::FieldValue v = f.get(sim::RunResult{});
      std::visit([&](const auto& x) { fields.emplace_back(std::vector<std::decay_t<decltype(x)>>(n)); }, v);
    }
  }
  void store(std::size_t i, sim::RunResult&& r) {
    status[i] = static_cast<std::int64_t>(r.status);
    const auto& table = io::run_result_fields();
    for (std::size_t k = 0; k < table.size(); ++k)
      std::visit(
          [&](auto& col) { col[i] = std::get<typename std::decay_t<decltype(col)>::value_type>(table[k].get(r)); },
          fields[k]);
    message[i] = std::move(r.message);
    if (!bays.empty()) bays[i] = std::move(r.bays);
  }
};

// A failed run's error, to raise once every thread has stopped.
struct Failure {
  std::size_t index = std::numeric_limits<std::size_t>::max();
  std::string message;
  bool bad_input = false;
};

// work(i) for i in [0, n) on `threads` threads (the calling one among them), the GIL released.
// The first failure (lowest index) stops the rest; between its own runs the calling thread checks
// for signals every 50 ms, so that Ctrl-C stops the batch (KeyboardInterrupt) after the runs under way.
template <class Work>
Failure run_parallel(std::size_t n, int threads, const Work& work) {
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::mutex mutex;
  Failure failure;
  bool interrupted = false;
  auto fail = [&](std::size_t i, std::string msg, bool bad_input) {
    std::lock_guard lock(mutex);
    if (i < failure.index) failure = {i, std::move(msg), bad_input};
    stop = true;
  };
  auto loop = [&](bool poll_signals) {
    auto last_poll = std::chrono::steady_clock::now();
    for (std::size_t i; !stop && (i = next++) < n;) {
      try {
        work(i);
      } catch (const io::InputError& e) {
        fail(i, e.what(), true);
      } catch (const std::exception& e) {
        fail(i, fmt::format("internal error in the simulation: {}", e.what()), false);
      }
      if (poll_signals && std::chrono::steady_clock::now() - last_poll > std::chrono::milliseconds(50)) {
        last_poll = std::chrono::steady_clock::now();
        pyb::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) interrupted = stop = true;  // the exception stays set in this thread
      }
    }
  };
  {
    pyb::gil_scoped_release nogil;
    std::vector<std::thread> pool;
    for (int t = 1; t < threads && static_cast<std::size_t>(t) < n; ++t) pool.emplace_back(loop, false);
    loop(true);
    for (auto& t : pool) t.join();
  }
  if (interrupted) throw pyb::error_already_set();
  return failure;
}

// The columns as Python objects: numeric ones as numpy arrays, strings as lists; per-bay columns
// "FIELD[bay J]" (J = 1..the largest bay count; NaN past a run's own bays).
pyb::dict to_columns(Outcome& o) {
  pyb::dict d;
  d["status"] = pyb::array_t<std::int64_t>(static_cast<pyb::ssize_t>(o.status.size()), o.status.data());
  d["message"] = pyb::cast(o.message);
  const auto& table = io::run_result_fields();
  for (std::size_t k = 0; k < table.size(); ++k)
    std::visit(
        [&](auto& col) {
          using T = typename std::decay_t<decltype(col)>::value_type;
          if constexpr (std::is_same_v<T, std::string>)
            d[table[k].name] = pyb::cast(col);
          else
            d[table[k].name] = pyb::array_t<T>(static_cast<pyb::ssize_t>(col.size()), col.data());
        },
        o.fields[k]);
  std::size_t max_bays = 0;
  for (const auto& b : o.bays) max_bays = std::max(max_bays, b.size());
  for (const auto& f : io::bay_result_fields()) {
    if (!std::holds_alternative<double>(f.get(sim::BayResult{}))) continue;  // the bay number: in the name
    for (std::size_t j = 0; j < max_bays; ++j) {
      pyb::array_t<double> a(static_cast<pyb::ssize_t>(o.bays.size()));
      for (std::size_t i = 0; i < o.bays.size(); ++i)
        a.mutable_at(i) =
            j < o.bays[i].size() ? std::get<double>(f.get(o.bays[i][j])) : std::numeric_limits<double>::quiet_NaN();
      d[pyb::str(fmt::format("{}[bay {}]", f.name, j + 1))] = a;
    }
  }
  return d;
}

// Raises the failure, if any; warns once for the runs with plausibility warnings.
void finish(const Failure& f, const Outcome& o) {
  if (!f.message.empty()) {
    const std::string msg = fmt::format("simulate_many: run {}: {}", f.index, f.message);
    if (f.bad_input) throw pyb::value_error(msg);
    throw std::runtime_error(msg);
  }
  std::size_t warned = 0, first = 0;
  for (std::size_t i = o.warning.size(); i-- > 0;)
    if (!o.warning[i].empty()) ++warned, first = i;
  if (warned == 0) return;
  const std::string w = fmt::format("simulate_many: {} of {} runs set a key outside its typical range; run {}: {}",
                                    warned, o.warning.size(), first, o.warning[first]);
  if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) != 0) throw pyb::error_already_set();
}

// One run of simulate_many: no histories (the rows hold summaries).
sim::RunResult run_one(sim::SceneOptions o, const std::string& source) {
  o.run.output_step_s = 0.0;
  sim::RunResult r = sim::simulate(o);
  if (r.status == sim::RunStatus::invalid_input) throw io::InputError(fmt::format("error: {}: {}", source, r.message));
  return r;
}

pyb::dict many_scenes(const pyb::sequence& scenes, int threads, bool bays) {
  // Copies: the runs read no Python object once the GIL is released.
  std::vector<Scene> copies;
  copies.reserve(scenes.size());
  for (const auto item : scenes) {
    const auto& s = item.cast<const Scene&>();
    copies.push_back({{}, s.source, {}, s.options});
  }
  Outcome out(copies.size(), bays);
  const Failure f = run_parallel(copies.size(), threads,
                                 [&](std::size_t i) { out.store(i, run_one(copies[i].options, copies[i].source)); });
  finish(f, out);
  return to_columns(out);
}

pyb::dict many_settings(const Scene& base, const pyb::sequence& rows, int threads, bool bays) {
  std::vector<std::vector<io::SceneSetting>> settings;
  settings.reserve(rows.size());
  for (const auto row : rows) {
    std::vector<io::SceneSetting> s;
    for (auto [k, v] : pyb::dict(pyb::reinterpret_borrow<pyb::object>(row)))
      s.push_back({setting_text(pyb::str(k), v), {}});
    settings.push_back(std::move(s));
  }
  const Scene b = base;
  Outcome out(settings.size(), bays);
  const Failure f = run_parallel(settings.size(), threads, [&](std::size_t i) {
    std::vector<std::string> warnings;  // for the keys the row sets (the base's were given with it)
    const sim::SceneOptions o =
        io::parse_scene_variant(b.options, b.text, b.source, b.settings, settings[i], &warnings);
    if (!warnings.empty()) out.warning[i] = warnings.front();
    out.store(i, run_one(o, b.source));
  });
  finish(f, out);
  return to_columns(out);
}

}  // namespace

void bind_many(pyb::module_& m) {
  m.def("simulate_many_scenes", &many_scenes, pyb::arg("scenes"), pyb::arg("threads"), pyb::arg("bays"),
        "Columns of the runs of a list of scenes (truss_deploy.simulate_many builds the DataFrame).");
  m.def("simulate_many_settings", &many_settings, pyb::arg("base"), pyb::arg("rows"), pyb::arg("threads"),
        pyb::arg("bays"), "Columns of the runs of a base scene with one mapping of settings per run.");
}

}  // namespace truss::py
