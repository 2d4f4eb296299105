// truss_deploy._core.simulate_many_*: many runs on parallel threads with the GIL released, their
// summaries gathered into columns (one per field of the JSON summary's tables), one row per run.
// The pure-Python simulate_many (truss_deploy/__init__.py) turns the columns into a DataFrame.
//
// The numeric columns are numpy arrays allocated before the runs (the bay count of every scene is
// known by then); each worker thread writes its run's row into them as the run ends, so that no
// result is kept and nothing is gathered afterwards under the GIL (that serial step limited two
// threads to 1.6x). Workers take runs in blocks, so that two threads seldom write one cache line.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <algorithm>
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

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One column: a numpy array (its data written by the workers) or the strings of a str field.
struct Column {
  pyb::object array;              // numpy array of double or int64, or None for strings
  void* data = nullptr;           // the array's data
  std::vector<std::string> text;  // a str field's values
  enum class Kind { f64, i64, str } kind = Kind::f64;
};

// The numeric columns of one type as the rows of one 2-D array (rows x runs): one allocation, which
// numpy backs with huge pages from 4 MiB on, so that a run's row, one value in each of ~400 columns,
// touches a few pages rather than ~400 (a TLB miss each: 4 % of a Table-1 run).
template <class T>
class ColumnBlock {
 public:
  ColumnBlock(std::size_t rows, std::size_t n)
      : block_({static_cast<pyb::ssize_t>(rows), static_cast<pyb::ssize_t>(n)}), n_(n) {}
  Column take() {
    const auto row = static_cast<pyb::ssize_t>(next_++);
    return {block_[pyb::int_(row)], block_.mutable_data() + row * static_cast<pyb::ssize_t>(n_), {},
            std::is_same_v<T, double> ? Column::Kind::f64 : Column::Kind::i64};
  }

 private:
  pyb::array_t<T> block_;
  std::size_t n_, next_ = 0;
};

// Every column of the batch, and the warnings of the runs' settings.
struct Outcome {
  Column status, message;
  std::vector<Column> fields;  // io::run_result_fields(), in order
  // bay_fields[f][j]: field f (a double field of io::bay_result_fields(); the bay number is in the
  // name) of bay j + 1, for j < the largest bay count; NaN past a run's own bays.
  std::vector<std::vector<Column>> bay_fields;
  std::vector<const io::BayField*> bay_sources;  // the bay_fields' fields of the table
  std::vector<std::string> warning;  // first plausibility warning of each run ("" if none)

  Outcome(std::size_t n, std::size_t max_bays) : warning(n) {
    std::size_t n_f64 = 0, n_i64 = 1;  // the status among the integers
    for (const auto& f : io::run_result_fields()) {
      const io::FieldValue v = f.get(sim::RunResult{});
      n_f64 += std::holds_alternative<double>(v);
      n_i64 += std::holds_alternative<std::int64_t>(v);
    }
    if (max_bays > 0)
      for (const auto& f : io::bay_result_fields()) {
        if (std::holds_alternative<double>(f.get(sim::BayResult{}))) bay_sources.push_back(&f);
      }
    ColumnBlock<double> f64(n_f64 + bay_sources.size() * max_bays, n);
    ColumnBlock<std::int64_t> i64(n_i64, n);
    status = i64.take();
    message.kind = Column::Kind::str;
    message.text.resize(n);
    for (const auto& f : io::run_result_fields()) {
      const io::FieldValue v = f.get(sim::RunResult{});
      if (std::holds_alternative<double>(v)) fields.push_back(f64.take());
      else if (std::holds_alternative<std::int64_t>(v)) fields.push_back(i64.take());
      else fields.push_back({pyb::none(), nullptr, std::vector<std::string>(n), Column::Kind::str});
    }
    for (std::size_t f = 0; f < bay_sources.size(); ++f) {
      auto& per_bay = bay_fields.emplace_back();
      for (std::size_t j = 0; j < max_bays; ++j) per_bay.push_back(f64.take());
    }
  }
  // Row i from run r (each run writes its own row only; no GIL needed).
  void store(std::size_t i, sim::RunResult&& r) {
    static_cast<std::int64_t*>(status.data)[i] = static_cast<std::int64_t>(r.status);
    const auto& table = io::run_result_fields();
    for (std::size_t k = 0; k < table.size(); ++k) {
      Column& c = fields[k];
      const io::FieldValue v = table[k].get(r);
      if (c.kind == Column::Kind::f64) static_cast<double*>(c.data)[i] = std::get<double>(v);
      else if (c.kind == Column::Kind::i64) static_cast<std::int64_t*>(c.data)[i] = std::get<std::int64_t>(v);
      else c.text[i] = std::get<std::string>(v);
    }
    message.text[i] = std::move(r.message);
    if (bay_fields.empty()) return;
    if (r.bays.size() > bay_fields.front().size())
      throw std::logic_error(fmt::format("a run gave {} bays for a scene of at most {}", r.bays.size(),
                                         bay_fields.front().size()));
    for (std::size_t f = 0; f < bay_fields.size(); ++f) {
      const auto get = bay_sources[f]->get;
      auto& per_bay = bay_fields[f];
      for (std::size_t j = 0; j < per_bay.size(); ++j)
        static_cast<double*>(per_bay[j].data)[i] = j < r.bays.size() ? std::get<double>(get(r.bays[j])) : kNaN;
    }
  }
};

// The columns as Python objects: numeric ones the numpy arrays, strings as lists; per-bay columns
// "FIELD[bay J]".
pyb::dict to_columns(Outcome& o) {
  pyb::dict d;
  d["status"] = o.status.array;
  d["message"] = pyb::cast(o.message.text);
  const auto& table = io::run_result_fields();
  for (std::size_t k = 0; k < table.size(); ++k)
    d[table[k].name] = o.fields[k].kind == Column::Kind::str ? pyb::cast(o.fields[k].text) : o.fields[k].array;
  for (std::size_t f = 0; f < o.bay_fields.size(); ++f)
    for (std::size_t j = 0; j < o.bay_fields[f].size(); ++j)
      d[pyb::str(fmt::format("{}[bay {}]", o.bay_sources[f]->name, j + 1))] = o.bay_fields[f][j].array;
  return d;
}

// A failed run's error, to raise once every thread has stopped.
struct Failure {
  std::size_t index = std::numeric_limits<std::size_t>::max();
  std::string message;
  bool bad_input = false;
};

// work(i) for i in [0, n) on `threads` threads (the calling one among them), the GIL released.
// The first failure (lowest index) stops the rest; between its own runs the calling thread checks
// for signals every 50 ms, so that Ctrl-C stops the batch (KeyboardInterrupt) after the runs under way.
// Runs are handed out in blocks of consecutive indices (rows of the same cache lines to one thread).
template <class Work>
Failure run_parallel(std::size_t n, int threads, const Work& work) {
  const std::size_t block = std::clamp<std::size_t>(n / (8 * static_cast<std::size_t>(threads)), 1, 32);
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
    for (std::size_t first; !stop && (first = next.fetch_add(block)) < n;) {
      for (std::size_t i = first; i < std::min(n, first + block) && !stop; ++i) {
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
    }
  };
  {
    pyb::gil_scoped_release nogil;
    std::vector<std::thread> pool;
    for (int t = 1; t < threads && static_cast<std::size_t>(t) * block < n; ++t) pool.emplace_back(loop, false);
    loop(true);
    for (auto& t : pool) t.join();
  }
  if (interrupted) throw pyb::error_already_set();
  return failure;
}

// Raises the failure, if any.
void raise_failure(const Failure& f) {
  if (f.message.empty()) return;
  const std::string msg = fmt::format("simulate_many: run {}: {}", f.index, python_message(f.message));
  if (f.bad_input) throw pyb::value_error(msg);
  throw std::runtime_error(msg);
}

// Warns once for the runs with plausibility warnings.
void warn_once(const std::vector<std::string>& warning) {
  std::size_t warned = 0, first = 0;
  for (std::size_t i = warning.size(); i-- > 0;)
    if (!warning[i].empty()) ++warned, first = i;
  if (warned == 0) return;
  const std::string w = fmt::format("simulate_many: {} of {} runs set a key outside its typical range; run {}: {}",
                                    warned, warning.size(), first, python_message(warning[first]));
  if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) != 0) throw pyb::error_already_set();
}

// The runs of the scenes into the columns (no histories: the rows hold summaries).
pyb::dict run_all(std::vector<sim::SceneOptions>& scenes, const std::vector<std::string>& sources, int threads,
                  bool bays, std::vector<std::string> warnings) {
  std::size_t max_bays = 0;
  if (bays)
    for (const auto& s : scenes) max_bays = std::max(max_bays, static_cast<std::size_t>(std::max(s.mast.n_bays, 0)));
  Outcome out(scenes.size(), max_bays);
  out.warning = std::move(warnings);
  const Failure f = run_parallel(scenes.size(), threads, [&](std::size_t i) {
    scenes[i].run.output_step_s = 0.0;
    sim::RunResult r = sim::simulate(scenes[i]);
    const std::string& source = sources[sources.size() == 1 ? 0 : i];
    if (r.status == sim::RunStatus::invalid_input)
      throw io::InputError(fmt::format("error: {}: {}", source, r.message));
    out.store(i, std::move(r));
  });
  raise_failure(f);
  warn_once(out.warning);
  return to_columns(out);
}

pyb::dict many_scenes(const pyb::sequence& scenes, int threads, bool bays) {
  // Copies: the runs read no Python object once the GIL is released.
  std::vector<sim::SceneOptions> options;
  std::vector<std::string> sources;
  options.reserve(scenes.size());
  sources.reserve(scenes.size());
  for (const auto item : scenes) {
    const auto& s = item.cast<const Scene&>();
    options.push_back(s.options);
    sources.push_back(s.source);
  }
  return run_all(options, sources, threads, bays, std::vector<std::string>(options.size()));
}

pyb::dict many_settings(const Scene& base, const pyb::sequence& rows, int threads, bool bays) {
  std::vector<std::vector<io::SceneSetting>> settings;
  settings.reserve(rows.size());
  for (const auto row : rows) {
    std::vector<io::SceneSetting> s;
    for (auto [k, v] : pyb::dict(pyb::reinterpret_borrow<pyb::object>(row)))
      s.push_back(python_setting(pyb::str(k), v));
    settings.push_back(std::move(s));
  }
  // Every row read first (in parallel): a bad row raises before any run, and the bay counts size
  // the columns.
  const Scene b = base;
  std::vector<sim::SceneOptions> options(settings.size());
  std::vector<std::string> warning(settings.size());
  raise_failure(run_parallel(settings.size(), threads, [&](std::size_t i) {
    std::vector<std::string> w;  // for the keys the row sets (the base's were given with it)
    options[i] = io::parse_scene_variant(b.options, b.text, b.source, b.settings, settings[i], &w);
    if (!w.empty()) warning[i] = w.front();
  }));
  return run_all(options, {b.source}, threads, bays, std::move(warning));
}

}  // namespace

void bind_many(pyb::module_& m) {
  m.def("simulate_many_scenes", &many_scenes, pyb::arg("scenes"), pyb::arg("threads"), pyb::arg("bays"),
        "Columns of the runs of a list of scenes (truss_deploy.simulate_many builds the DataFrame).");
  m.def("simulate_many_settings", &many_settings, pyb::arg("base"), pyb::arg("rows"), pyb::arg("threads"),
        pyb::arg("bays"), "Columns of the runs of a base scene with one mapping of settings per run.");
}

}  // namespace truss::py
