// What the results file holds besides the per-run datasets (docs/hdf5-schema.md): /stats from the
// streamed statistics, /histories, the root attributes, the inputs' distributions and /timing's
// attributes.
#include "results/summary_h5.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "io/build_info.hpp"
#include "io/h5_util.hpp"
#include "results/read_back.hpp"
#include "sim/scene.hpp"

namespace truss::results {

using namespace io::h5;
using namespace campaign;
using statistics::Stats;

namespace {

void write_stats_group(hid_t loc, const Field& f, const std::vector<Stats>& s) {
  Handle g = create_group(loc, f.name);
  write_string_attribute(g.get(), "units", f.units);
  const bool vector = f.scale != Scale::none;
  const std::size_t n = s.size();
  std::vector<std::int64_t> count(n);
  std::vector<double> col(n);
  for (std::size_t i = 0; i < n; ++i) count[i] = s[i].count;
  auto put = [&](const char* field, auto get) {
    for (std::size_t i = 0; i < n; ++i) col[i] = get(s[i]);
    if (vector) write_array(g.get(), field, f.units.c_str(), col.data(), n);
    else write_scalar(g.get(), field, f.units, col[0]);
  };
  if (vector) write_array(g.get(), "count", "1", count.data(), n);
  else write_scalar(g.get(), "count", "1", count[0]);
  put("mean", [](const Stats& x) { return x.mean; });
  put("std", [](const Stats& x) { return x.std; });
  put("min", [](const Stats& x) { return x.min; });
  put("max", [](const Stats& x) { return x.max; });
  for (std::size_t k = 0; k < statistics::kStatPercentiles.size(); ++k)
    put(statistics::kStatPercentileNames[k], [k](const Stats& x) { return x.percentiles[k]; });
}

void write_stats_attributes(hid_t stats, const std::vector<std::int8_t>& status) {
  const auto n = static_cast<std::int64_t>(status.size());
  std::int64_t n_failed = 0;
  std::vector<std::int64_t> counts(sim::kRunStatusCount, 0);
  for (auto s : status) {
    n_failed += s != 0;
    ++counts[static_cast<std::size_t>(s)];
  }
  write_int_attribute(stats, "n_runs", n);
  write_int_attribute(stats, "n_ok", n - n_failed);
  write_int_attribute(stats, "n_failed", n_failed);
  write_string_attribute(stats, "percentile_method", "linear interpolation between order statistics (Hyndman-Fan "
                                                     "type 7, numpy.percentile default), exact");
  write_string_attribute(stats, "moments_method",
                         "per chunk of runs, combined in run-index order (Chan, Golub and LeVeque 1979)");
  write_int_attribute(stats, "std_ddof", 1);
  std::vector<std::string> names;
  for (int s = 0; s < sim::kRunStatusCount; ++s) names.emplace_back(sim::to_string(static_cast<sim::RunStatus>(s)));
  write_strings(stats, "status_names", names);
  write_array(stats, "status_counts", "1", counts.data(), counts.size());
}

}  // namespace

std::int64_t write_stats(hid_t file, const std::string& path, const RecordLayout& layout, StreamedStats streamed) {
  Handle rows(H5Dopen2(file, "runs/status", H5P_DEFAULT), H5Dclose, "open /runs/status");
  Handle space(H5Dget_space(rows.get()), H5Sclose, "space of /runs/status");
  const auto n = static_cast<std::int64_t>(H5Sget_simple_extent_npoints(space.get()));
  const std::vector<std::int8_t> status = read_status(file, n);
  std::vector<std::uint8_t> ok(status.size());
  for (std::size_t i = 0; i < status.size(); ++i) ok[i] = status[i] == 0;
  // The columns no rank read back before (read_back.hpp), read back here the same way.
  for (const ReadBackJob& job : find_read_back(file, layout, streamed, n))
    apply_read_back(streamed, calc_read_back(path, job, ok));
  Handle stats = create_group(file, "stats");
  write_stats_attributes(stats.get(), status);
  Handle bays = create_group(stats.get(), "bays");
  std::size_t k = 0, j = 0;  // the k-th float64 output, the j-th per-bay one
  for (const Field& f : layout.fields()) {
    if (!f.statistics) continue;
    if (f.scale == Scale::none) write_stats_group(stats.get(), f, {streamed.f64[k++]});
    else write_stats_group(bays.get(), f, streamed.bays[j++]);
  }
  return streamed.read_back;
}

void write_histories(hid_t file, double step_s, const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories) {
  if (histories.empty()) return;
  Handle g = create_group(file, "histories");
  write_double_attribute(g.get(), "step_s", step_s);
  for (const auto& [run, r] : histories) {
    Handle h = create_group(g.get(), fmt::format("run_{}", run));
    write_string_attribute(h.get(), "status", sim::to_string(r.status));
    write_history(h.get(), r.history);
  }
}

void write_root_attributes(hid_t file, const CampaignContext& ctx, std::int64_t n_runs, const CampaignFileInfo& info) {
  const CampaignOptions& c = ctx.options;
  write_int_attribute(file, "schema_version", kCampaignSchemaVersion);
  write_string_attribute(file, "kind", "campaign");
  write_string_attribute(file, "campaign_name", c.name);
  write_string_attribute(file, "campaign_description", c.description);
  write_string_attribute(file, "campaign_toml", info.campaign_toml);
  write_string_attribute(file, "base_scene_toml", info.base_scene_toml);
  write_int_attribute(file, "n_runs", n_runs);
  write_int_attribute(file, "n_rounds", info.n_rounds);
  write_int_attribute(file, "master_seed", static_cast<std::int64_t>(c.ensemble.master_seed));
  write_string_attribute(file, "sampling", to_string(c.ensemble.sampling));
  write_int_attribute(file, "n_bays_max", ctx.dims.n_bays_max);
  write_string_attribute(file, "direction", sim::to_string(c.base.run.direction));
  write_string_attribute(file, "drive_mode", sim::to_string(c.base.drive.mode));
  write_string_attribute(file, "motor_declared_by", info.motor_declared_by);
  write_string_attribute(file, "software_version", std::string(io::get_software_version()));
  write_string_attribute(file, "git_revision", std::string(io::get_git_revision()));
  write_int_attribute(file, "n_ranks", info.n_ranks);
  write_int_attribute(file, "n_sessions", info.n_sessions);
  write_string_attribute(file, "start_utc", info.start_utc);
  write_string_attribute(file, "end_utc", info.end_utc);
  write_double_attribute(file, "wall_time_s", info.wall_time_s);
}

void write_input_attributes(hid_t file, const CampaignOptions& c) {
  for (std::size_t d = 0; d < c.dispersions.size(); ++d) {
    const DispersionOptions& disp = c.dispersions[d];
    const std::string path = "runs/inputs/" + disp.key;
    Handle ds(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose, "open " + path);
    write_string_attribute(ds.get(), "per", to_string(disp.per));
    write_string_attribute(ds.get(), "apply", to_string(disp.apply));
    write_string_attribute(ds.get(), "distribution", to_string(disp.distribution));
    const DistributionKind k = disp.distribution;
    if (k == DistributionKind::normal || k == DistributionKind::truncated_normal) {
      write_double_attribute(ds.get(), "mean", disp.mean);
      write_double_attribute(ds.get(), "std", disp.std);
    }
    if (k == DistributionKind::truncated_normal || k == DistributionKind::uniform) {
      write_double_attribute(ds.get(), "lower", disp.lower);
      write_double_attribute(ds.get(), "upper", disp.upper);
    }
    if (k == DistributionKind::lognormal) {
      write_double_attribute(ds.get(), "mu", disp.mu);
      write_double_attribute(ds.get(), "sigma", disp.sigma);
    }
    if (k == DistributionKind::discrete) {
      write_doubles_attribute(ds.get(), "values", disp.values);
      write_doubles_attribute(ds.get(), "weights",
                              disp.weights.empty() ? std::vector<double>(disp.values.size(), 1.0) : disp.weights);
    }
    write_double_attribute(ds.get(), "nominal", find_nominal(c.base, disp.key));
    write_int_attribute(ds.get(), "factor", static_cast<std::int64_t>(d));
  }
}

void write_timing_attributes(hid_t file, const ScheduleSummary& s, std::int64_t stats_read_back) {
  Handle g(H5Gopen2(file, "timing", H5P_DEFAULT), H5Gclose, "open /timing");
  write_string_attribute(g.get(), "note", "not reproducible: depends on the machine, the ranks and the order of work");
  const std::pair<const char*, double> seconds[] = {
      {"schedule_wall_s", s.schedule_wall_s},       {"rank0_compute_s", s.rank0_compute_s},
      {"rank0_poll_s", s.rank0_poll_s},             {"rank0_mpi_s", s.rank0_mpi_s},
      {"rank0_result_s", s.rank0_result_s},         {"rank0_write_s", s.rank0_write_s},
      {"rank0_tick_s", s.rank0_tick_s},
      {"rank0_idle_s", s.rank0_idle_s},             {"rank0_handle_cpu_s", s.rank0_handle_cpu_s},
      {"rank0_compute_cpu_s", s.rank0_compute_cpu_s}, {"stats_merge_cpu_s", s.stats_merge_cpu_s}};
  for (const auto& [name, v] : seconds) write_double_attribute(g.get(), name, v);
  write_int_attribute(g.get(), "runs_by_rank0", s.runs_by_rank0);
  write_int_attribute(g.get(), "runs_by_workers", s.runs_by_workers);
  write_int_attribute(g.get(), "statistics_ranks", s.statistics_ranks);
  // Columns whose percentiles the end read back from /runs (their order statistics were outside
  // the streamed windows): depends on which chunk was written first, hence here.
  write_int_attribute(g.get(), "stats_columns_read_back", stats_read_back);
  write_int_attribute(g.get(), "stats_read_back_ranks", s.stats_read_back_ranks);
  if (s.synthetic_run_cost_s >= 0) write_double_attribute(g.get(), "synthetic_run_cost_s", s.synthetic_run_cost_s);
}

}  // namespace truss::results
