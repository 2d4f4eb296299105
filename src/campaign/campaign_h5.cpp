#include "campaign/campaign_h5.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "campaign/progress.hpp"
#include "campaign/result_store.hpp"

#include "io/h5_util.hpp"
#include "io/json_summary.hpp"
#include "sim/scene.hpp"

namespace truss::campaign {

using namespace io::h5;
namespace fs = std::filesystem;

namespace {

Handle make_group(hid_t loc, const std::string& name) {
  return Handle(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create group " + name);
}

void write_double_attribute(hid_t obj, const char* name, double v) {
  Handle space = scalar_space();
  Handle a(H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
           fmt::format("create attribute {}", name));
  check(H5Awrite(a.get(), H5T_NATIVE_DOUBLE, &v), fmt::format("write attribute {}", name));
}

void write_doubles_attribute(hid_t obj, const char* name, const std::vector<double>& v) {
  Handle space = vector_space(v.size());
  Handle a(H5Acreate2(obj, name, H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
           fmt::format("create attribute {}", name));
  if (!v.empty()) check(H5Awrite(a.get(), H5T_NATIVE_DOUBLE, v.data()), fmt::format("write attribute {}", name));
}

void write_scalar_double(hid_t loc, const char* name, const std::string& units, double v) {
  Handle space = scalar_space();
  Handle ds = create_dataset(loc, name, H5T_IEEE_F64LE, space.get());
  check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), std::string("write ") + name);
  write_string_attribute(ds.get(), "units", units);
}

void write_scalar_int(hid_t loc, const char* name, std::int64_t v) {
  Handle space = scalar_space();
  Handle ds = create_dataset(loc, name, H5T_STD_I64LE, space.get());
  check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), std::string("write ") + name);
  write_string_attribute(ds.get(), "units", "1");
}

void write_strings(hid_t loc, const std::string& name, const std::vector<std::string>& v) {
  Handle type = string_type();
  Handle space = vector_space(v.size());
  Handle ds = create_dataset(loc, name, type.get(), space.get());
  std::vector<const char*> p;
  for (const auto& s : v) p.push_back(s.c_str());
  if (!p.empty()) check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), "write " + name);
  write_string_attribute(ds.get(), "units", "1");
}

void write_stats_group(hid_t loc, const std::string& name, const std::string& units, const std::vector<Stats>& s, bool vector) {
  Handle g = make_group(loc, name);
  write_string_attribute(g.get(), "units", units.c_str());
  const std::size_t n = s.size();
  std::vector<std::int64_t> count(n);
  std::vector<double> col(n);
  for (std::size_t i = 0; i < n; ++i) count[i] = s[i].count;
  auto put = [&](const char* field, auto get) {
    for (std::size_t i = 0; i < n; ++i) col[i] = get(s[i]);
    if (vector) write_array(g.get(), field, units.c_str(), col.data(), n);
    else write_scalar_double(g.get(), field, units, col[0]);
  };
  if (vector) write_array(g.get(), "count", "1", count.data(), n);
  else write_scalar_int(g.get(), "count", count[0]);
  put("mean", [](const Stats& x) { return x.mean; });
  put("std", [](const Stats& x) { return x.std; });
  put("min", [](const Stats& x) { return x.min; });
  put("max", [](const Stats& x) { return x.max; });
  for (std::size_t k = 0; k < kStatPercentiles.size(); ++k)
    put(kStatPercentileNames[k], [k](const Stats& x) { return x.percentiles[k]; });
}

const char* per_name(Per p) { return p == Per::run ? "run" : p == Per::bay ? "bay" : "frame"; }
const char* apply_name(Apply a) { return a == Apply::absolute ? "absolute" : a == Apply::relative ? "relative" : "offset"; }

// Root attributes: what the campaign was, and where and when it ran.
void write_root_attributes(hid_t file, const CampaignContext& ctx, const CampaignFileInfo& info) {
  const CampaignOptions& c = ctx.options;
  const OutputColumns& cols = ctx.columns;
  write_int_attribute(file, "schema_version", kCampaignSchemaVersion);
  write_string_attribute(file, "kind", "campaign");
  write_string_attribute(file, "campaign_name", c.name);
  write_string_attribute(file, "campaign_description", c.description);
  write_string_attribute(file, "campaign_toml", info.campaign_toml);
  write_string_attribute(file, "base_scene_toml", info.base_scene_toml);
  write_int_attribute(file, "n_runs", c.ensemble.n_runs);
  write_int_attribute(file, "master_seed", static_cast<std::int64_t>(c.ensemble.master_seed));
  write_string_attribute(file, "sampling", to_string(c.ensemble.sampling));
  write_int_attribute(file, "n_bays_max", cols.n_bays_max);
  write_string_attribute(file, "direction", sim::to_string(c.base.run.direction));
  write_string_attribute(file, "drive_mode", sim::to_string(c.base.drive.mode));
  write_string_attribute(file, "software_version", TRUSS_VERSION);
  write_string_attribute(file, "git_revision", TRUSS_GIT_REV);
  write_int_attribute(file, "n_ranks", info.n_ranks);
  write_int_attribute(file, "n_sessions", info.n_sessions);
  write_string_attribute(file, "start_utc", info.start_utc);
  write_string_attribute(file, "end_utc", info.end_utc);
  write_double_attribute(file, "wall_time_s", info.wall_time_s);
}

// /runs/inputs/KEY (written by the ResultStore): the dispersion's distribution as attributes.
void write_input_attributes(hid_t file, const CampaignContext& ctx) {
  const CampaignOptions& c = ctx.options;
  for (std::size_t d = 0; d < c.dispersions.size(); ++d) {
    const DispersionOptions& disp = c.dispersions[d];
    const std::string path = "runs/inputs/" + disp.key;
    Handle ds(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose, "open " + path);
    write_string_attribute(ds.get(), "per", per_name(disp.per));
    write_string_attribute(ds.get(), "apply", apply_name(disp.apply));
    write_string_attribute(ds.get(), "distribution", to_string(disp.distribution));
    if (disp.distribution == DistributionKind::normal || disp.distribution == DistributionKind::truncated_normal) {
      write_double_attribute(ds.get(), "mean", disp.mean);
      write_double_attribute(ds.get(), "std", disp.std);
    }
    if (disp.distribution == DistributionKind::truncated_normal || disp.distribution == DistributionKind::uniform) {
      write_double_attribute(ds.get(), "lower", disp.lower);
      write_double_attribute(ds.get(), "upper", disp.upper);
    }
    if (disp.distribution == DistributionKind::lognormal) {
      write_double_attribute(ds.get(), "mu", disp.mu);
      write_double_attribute(ds.get(), "sigma", disp.sigma);
    }
    if (disp.distribution == DistributionKind::discrete) {
      write_doubles_attribute(ds.get(), "values", disp.values);
      write_doubles_attribute(ds.get(), "weights", disp.weights.empty() ? std::vector<double>(disp.values.size(), 1.0) : disp.weights);
    }
    write_double_attribute(ds.get(), "nominal", find_nominal(c.base, disp.key));
    write_int_attribute(ds.get(), "factor", static_cast<std::int64_t>(d));
  }
}

// /stats: statistics of the ok runs, per output and per bay; status counts. The statistics are
// the store's streamed ones (column_stats.hpp); a column whose percentiles could not be resolved
// from the kept values is read back from /runs and its percentiles are calc_stats' (the same exact
// order statistics either way). Returns the number of columns read back.
std::int64_t write_stats(hid_t file, const CampaignContext& ctx, const std::vector<std::int8_t>& status, StreamedStats streamed,
                         std::int64_t chunk_rows) {
  const OutputColumns& cols = ctx.columns;
  const auto n = static_cast<std::int64_t>(status.size());
  std::int64_t n_failed = 0;
  std::vector<std::uint8_t> ok(status.size());
  for (std::size_t i = 0; i < status.size(); ++i) {
    ok[i] = status[i] == 0;
    n_failed += status[i] != 0;
  }
  Handle stats = make_group(file, "stats");
  write_int_attribute(stats.get(), "n_runs", n);
  write_int_attribute(stats.get(), "n_ok", n - n_failed);
  write_int_attribute(stats.get(), "n_failed", n_failed);
  write_string_attribute(stats.get(), "percentile_method",
                         "linear interpolation between order statistics (Hyndman-Fan type 7, numpy.percentile default), exact");
  write_string_attribute(stats.get(), "moments_method",
                         "per chunk of runs, combined in run-index order (Chan, Golub and LeVeque 1979)");
  write_int_attribute(stats.get(), "std_ddof", 1);
  std::vector<std::string> names;
  std::vector<std::int64_t> counts(sim::kRunStatusCount, 0);
  for (int s = 0; s < sim::kRunStatusCount; ++s) names.emplace_back(sim::to_string(static_cast<sim::RunStatus>(s)));
  for (auto s : status) ++counts[static_cast<std::size_t>(s)];
  write_strings(stats.get(), "status_names", names);
  write_array(stats.get(), "status_counts", "1", counts.data(), counts.size());
  std::int64_t read_back = 0;
  auto resolve = [&](Stats& st, const std::vector<double>& column) {
    st.percentiles = calc_stats(column, ok).percentiles;
    ++read_back;
  };
  for (std::size_t k = 0; k < cols.f64.size(); ++k) {
    const std::string name = cols.f64[k]->name;
    if (!streamed.f64_resolved[k]) resolve(streamed.f64[k], read_f64_column(file, "runs/" + name, n));
    write_stats_group(stats.get(), name, cols.f64[k]->units, {streamed.f64[k]}, false);
  }
  Handle bays = make_group(stats.get(), "bays");
  const std::int64_t nb = cols.n_bays_max;
  for (std::size_t k = 0; k < cols.bay.size(); ++k) {
    const std::string path = "runs/bays/" + std::string(cols.bay[k]->name);
    for (std::int64_t b = 0; b < nb; ++b)
      if (!streamed.bays_resolved[k][static_cast<std::size_t>(b)])
        resolve(streamed.bays[k][static_cast<std::size_t>(b)], read_f64_columns(file, path, n, nb, b, 1, chunk_rows).front());
    write_stats_group(bays.get(), cols.bay[k]->name, cols.bay[k]->units, streamed.bays[k], true);
  }
  return read_back;
}

void write_sensitivity(hid_t file, const CampaignContext& ctx, const std::vector<std::int8_t>& status) {
  const CampaignOptions& c = ctx.options;
  if (c.ensemble.sampling != SamplingMethod::saltelli) return;
  const auto n = static_cast<std::int64_t>(status.size());
  const auto sens = calc_sensitivity(status, ctx.columns, c,
                                     [&](const std::string& name) { return read_f64_column(file, "runs/" + name, n); });
  Handle g = make_group(file, "sensitivity");
  std::vector<std::string> factors;
  for (const auto& d : c.dispersions) factors.push_back(d.key);
  write_strings(g.get(), "factor", factors);
  for (const auto& s : sens) {
    Handle o = make_group(g.get(), s.output);
    const auto G = static_cast<std::size_t>(s.indices.d);
    write_array(o.get(), "first_order", "1", s.indices.first_order.data(), G);
    write_array(o.get(), "first_order_lo", "1", s.indices.first_order_lo.data(), G);
    write_array(o.get(), "first_order_hi", "1", s.indices.first_order_hi.data(), G);
    write_array(o.get(), "total", "1", s.indices.total.data(), G);
    write_array(o.get(), "total_lo", "1", s.indices.total_lo.data(), G);
    write_array(o.get(), "total_hi", "1", s.indices.total_hi.data(), G);
    write_int_attribute(o.get(), "n_blocks", s.n_blocks);
    write_int_attribute(o.get(), "n_blocks_dropped", s.n_blocks_dropped);
    write_int_attribute(o.get(), "n_resamples", s.indices.n_resamples);
    write_double_attribute(o.get(), "confidence", s.indices.confidence);
    write_string_attribute(o.get(), "method",
                           "Saltelli et al. 2010 design with one factor per dispersion; first order: Saltelli 2010 "
                           "estimator; total: Jansen 1999; intervals: percentile bootstrap over blocks");
  }
}

void write_histories(hid_t file, const CampaignOptions& c, const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories) {
  if (!histories.empty()) {
    Handle g = make_group(file, "histories");
    write_double_attribute(g.get(), "step_s", c.output.history_step_s);
    for (const auto& [run, r] : histories) {
      Handle h = make_group(g.get(), fmt::format("run_{}", run));
      write_string_attribute(h.get(), "status", sim::to_string(r.status));
      write_history(h.get(), r.history);
    }
  }
}

// /timing's per-run datasets are the ResultStore's; the schedule of this session as attributes.
void write_timing_attributes(hid_t file, const CampaignFileInfo& info, std::int64_t stats_read_back) {
  Handle g(H5Gopen2(file, "timing", H5P_DEFAULT), H5Gclose, "open /timing");
  write_string_attribute(g.get(), "note", "not reproducible: depends on the machine, the ranks and the order of work");
  const ScheduleTiming& st = info.schedule;
  write_double_attribute(g.get(), "schedule_wall_s", st.wall_s);
  write_double_attribute(g.get(), "rank0_compute_s", st.rank0_compute_s);
  write_double_attribute(g.get(), "rank0_poll_s", st.rank0_poll_s);
  write_double_attribute(g.get(), "rank0_tick_s", st.rank0_tick_s);
  write_double_attribute(g.get(), "rank0_mpi_s", st.rank0_mpi_s);
  write_double_attribute(g.get(), "rank0_result_s", st.rank0_result_s);
  write_double_attribute(g.get(), "rank0_journal_s", st.rank0_journal_s);
  write_double_attribute(g.get(), "rank0_job_output_s", st.rank0_job_output_s);
  write_double_attribute(g.get(), "rank0_idle_s", st.rank0_idle_s);
  write_double_attribute(g.get(), "rank0_handle_cpu_s", st.rank0_handle_cpu_s);
  write_double_attribute(g.get(), "rank0_compute_cpu_s", st.rank0_compute_cpu_s);
  write_double_attribute(g.get(), "rank0_write_thread_cpu_s", st.rank0_write_thread_cpu_s);
  write_int_attribute(g.get(), "runs_by_rank0", st.runs_by_rank0);
  write_int_attribute(g.get(), "runs_by_workers", st.runs_by_workers);
  // Columns whose percentiles the end read back from /runs (their order statistics were outside
  // the streamed windows): depends on which chunk completed first, hence here.
  write_int_attribute(g.get(), "stats_columns_read_back", stats_read_back);
  if (st.synthetic_run_cost_s >= 0) write_double_attribute(g.get(), "synthetic_run_cost_s", st.synthetic_run_cost_s);
}

}  // namespace

std::string CampaignFile::temporary_name(const std::string& path) {
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path();
  return (dir / fmt::format(".{}.tmp.{}", p.filename().string(), static_cast<long>(::getpid()))).string();
}

CampaignFile::CampaignFile(const std::string& path, const CampaignContext& ctx, const StoreOptions& opts)
    : path_(path), tmp_(temporary_name(path)), ctx_(ctx), chunk_rows_(opts.chunk_runs) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through exceptions
  file_ = H5Fcreate(tmp_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file_ < 0) {
    tmp_.clear();
    throw_h5("create " + temporary_name(path));
  }
  try {
    store_ = std::make_unique<ResultStore>(file_, ctx, opts);
  } catch (...) {
    discard();
    throw;
  }
}

CampaignFile::~CampaignFile() { discard(); }

void CampaignFile::start_writeback() const {
  if (const auto task = writeback_task()) task();
}

std::function<void()> CampaignFile::writeback_task() const {
  // Advisory: a file system without sync_file_range (or any error here) only leaves more for the
  // final sync.
  void* handle = nullptr;
  if (file_ < 0 || H5Fget_vfd_handle(file_, H5P_DEFAULT, &handle) < 0 || handle == nullptr) return {};
  const int fd = ::fcntl(*static_cast<int*>(handle), F_DUPFD_CLOEXEC, 0);
  if (fd < 0) return {};
  auto owned = std::shared_ptr<int>(new int(fd), [](int* p) {
    ::close(*p);
    delete p;
  });
  return [owned] { (void)::sync_file_range(*owned, 0, 0, SYNC_FILE_RANGE_WRITE); };
}

void CampaignFile::discard() noexcept {
  store_.reset();
  if (file_ >= 0) H5Fclose(file_);
  file_ = -1;
  if (!tmp_.empty()) {
    std::error_code ec;
    fs::remove(tmp_, ec);
    tmp_.clear();
  }
}

void CampaignFile::finish(const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories, const CampaignFileInfo& info,
                          bool force) {
  store_->drain_jobs();
  store_->check_complete();
  StreamedStats streamed = store_->calc_stats();
  store_.reset();  // closes the per-run datasets
  const std::vector<std::int8_t> status = read_status(file_, ctx_.options.ensemble.n_runs);
  write_root_attributes(file_, ctx_, info);
  write_input_attributes(file_, ctx_);
  const std::int64_t read_back = write_stats(file_, ctx_, status, std::move(streamed), chunk_rows_);
  write_sensitivity(file_, ctx_, status);
  write_histories(file_, ctx_.options, histories);
  write_timing_attributes(file_, info, read_back);
  if (info.write_extra) info.write_extra(file_);
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL), "flush " + tmp_);
  const hid_t f = file_;
  file_ = -1;
  check(H5Fclose(f), "close " + tmp_);
  sync_file(tmp_);
  commit(tmp_, path_, force);
  tmp_.clear();
}

// The end summary's main design values: nominal, P99.865 and maximum over the ok runs, as the
// finished file's /stats holds them (rank 0 holds no result table, and the statistics were
// streamed while the runs arrived: nothing is recomputed here).
std::vector<DesignValue> read_design_values(const std::string& path, const OutputColumns& cols,
                                                 const sim::RunResult& nominal) {
  static const std::pair<const char*, const char*> shown[] = {
      {"peak_drive_force_N", "peak drive force"}, {"peak_drive_torque_Nm", "peak drive torque"},
      {"peak_pin_force_N", "peak rail pin force"}, {"peak_diagonal_tension_N", "peak diagonal tension"},
      {"peak_latch_energy_J", "peak latch energy"}, {"deploy_time_s", "deployment time"}};
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return {};
  auto read = [&](const std::string& ds_path) {
    double v = 0.0;
    const hid_t ds = H5Dopen2(file, ds_path.c_str(), H5P_DEFAULT);
    const herr_t e = ds < 0 ? -1 : H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v);
    if (ds >= 0) H5Dclose(ds);
    if (e < 0) throw std::runtime_error("read " + ds_path);
    return v;
  };
  std::vector<DesignValue> res;
  try {
    for (const auto& [name, label] : shown)
      for (const auto* f : cols.f64)
        if (std::string(f->name) == name)
          res.push_back({label, f->units, std::get<double>(f->get(nominal)), read(fmt::format("stats/{}/p99_865", name)),
                         read(fmt::format("stats/{}/max", name)),
                         static_cast<std::int64_t>(read(fmt::format("stats/{}/count", name)))});
  } catch (const std::exception&) {
    res.clear();  // the summary is a convenience: the file itself is complete
  }
  H5Fclose(file);
  return res;
}

std::string read_example_message(const std::string& path, std::int64_t n_runs, sim::RunStatus status) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return {};
  std::string res;
  try {
    const std::vector<std::int8_t> s = read_status(file, n_runs);
    const auto it = std::find(s.begin(), s.end(), static_cast<std::int8_t>(status));
    if (it != s.end()) {
      const auto run = static_cast<std::int64_t>(it - s.begin());
      res = fmt::format("run {}: {}", run, read_message(file, run));
    }
  } catch (const std::exception&) {
    res.clear();  // a convenience of the end summary, like read_design_values
  }
  H5Fclose(file);
  return res;
}

std::vector<std::string> CampaignFile::remove_stale(const std::string& path) {
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  const std::string prefix = "." + p.filename().string() + ".tmp.";
  const std::string mine = fs::path(temporary_name(path)).filename().string();
  std::vector<std::string> removed;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() <= prefix.size() || name.rfind(prefix, 0) != 0 || name == mine) continue;
    if (name.find_first_not_of("0123456789", prefix.size()) != std::string::npos) continue;  // .NAME.tmp.PID only
    if (fs::remove(e.path(), ec)) removed.push_back(e.path().string());
  }
  return removed;
}

}  // namespace truss::campaign
