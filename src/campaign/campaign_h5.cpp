#include "campaign/campaign_h5.hpp"

#include <fmt/format.h>

#include "io/h5_util.hpp"
#include "io/json_summary.hpp"
#include "sim/scene.hpp"

namespace truss::campaign {

using namespace io::h5;

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
void write_root_attributes(hid_t file, const CampaignContext& ctx, const ResultTable& t, const CampaignFileInfo& info) {
  const CampaignOptions& c = ctx.options;
  const OutputColumns& cols = ctx.columns;
  write_int_attribute(file, "schema_version", kCampaignSchemaVersion);
  write_string_attribute(file, "kind", "campaign");
  write_string_attribute(file, "campaign_name", c.name);
  write_string_attribute(file, "campaign_description", c.description);
  write_string_attribute(file, "campaign_toml", info.campaign_toml);
  write_string_attribute(file, "base_scene_toml", info.base_scene_toml);
  write_int_attribute(file, "n_runs", t.n_runs());
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

// /runs/inputs: the applied value of every dispersion, with its distribution as attributes.
void write_inputs(hid_t runs, const CampaignContext& ctx, const ResultTable& t) {
  const CampaignOptions& c = ctx.options;
  const OutputColumns& cols = ctx.columns;
  const auto n = static_cast<std::size_t>(t.n_runs());
  Handle g = make_group(runs, "inputs");
  const DimensionLayout& L = ctx.sampler.layout();
  std::vector<double> col;
  for (std::size_t d = 0; d < c.dispersions.size(); ++d) {
    const DispersionOptions& disp = c.dispersions[d];
    const auto w = static_cast<std::size_t>(L.count[d]), off = static_cast<std::size_t>(L.offset[d]);
    col.resize(n * w);
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < w; ++j) col[i * w + j] = t.inputs[i * static_cast<std::size_t>(cols.n_inputs) + off + j];
    const std::string units = find_key_units(disp.key);
    write_array(g.get(), disp.key, units.c_str(), col.data(), n, disp.per == Per::run ? 0 : w);
    Handle ds(H5Dopen2(g.get(), disp.key.c_str(), H5P_DEFAULT), H5Dclose, "open " + disp.key);
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

// /runs: one column per output, per-bay outputs as runs x bays.
void write_runs(hid_t file, const CampaignContext& ctx, const ResultTable& t) {
  const OutputColumns& cols = ctx.columns;
  const auto n = static_cast<std::size_t>(t.n_runs());
  const auto nb = static_cast<std::size_t>(cols.n_bays_max);
    Handle runs = make_group(file, "runs");
  std::vector<std::int64_t> index(n);
  for (std::size_t i = 0; i < n; ++i) index[i] = static_cast<std::int64_t>(i);
  write_array(runs.get(), "run_index", "1", index.data(), n);
  {
    Handle type = status_enum_type();
    Handle space = vector_space(n);
    Handle ds = create_dataset(runs.get(), "status", type.get(), space.get());
    if (n) check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, t.status.data()), "write /runs/status");
    write_string_attribute(ds.get(), "units", "1");
  }
  write_strings(runs.get(), "message", t.message);
  for (std::size_t k = 0; k < cols.f64.size(); ++k) write_array(runs.get(), cols.f64[k]->name, cols.f64[k]->units, t.f64[k].data(), n);
  for (std::size_t k = 0; k < cols.i64.size(); ++k) write_array(runs.get(), cols.i64[k]->name, cols.i64[k]->units, t.i64[k].data(), n);
  {
    Handle g = make_group(runs.get(), "bays");
    for (std::size_t k = 0; k < cols.bay.size(); ++k) write_array(g.get(), cols.bay[k]->name, cols.bay[k]->units, t.bays[k].data(), n, nb);
  }
  write_inputs(runs.get(), ctx, t);
}

// /stats: statistics of the ok runs, per output and per bay; status counts.
void write_stats(hid_t file, const CampaignContext& ctx, const ResultTable& t) {
  const OutputColumns& cols = ctx.columns;
  const auto n = static_cast<std::size_t>(t.n_runs());
  const auto nb = static_cast<std::size_t>(cols.n_bays_max);
  std::vector<std::uint8_t> ok(n);
  for (std::size_t i = 0; i < n; ++i) ok[i] = t.status[i] == 0;
    Handle stats = make_group(file, "stats");
  write_int_attribute(stats.get(), "n_runs", t.n_runs());
  write_int_attribute(stats.get(), "n_ok", t.n_runs() - t.n_failed());
  write_int_attribute(stats.get(), "n_failed", t.n_failed());
  write_string_attribute(stats.get(), "percentile_method",
                         "linear interpolation between order statistics (Hyndman-Fan type 7, numpy.percentile default)");
  write_int_attribute(stats.get(), "std_ddof", 1);
  std::vector<std::string> names;
  std::vector<std::int64_t> counts(sim::kRunStatusCount, 0);
  for (int s = 0; s < sim::kRunStatusCount; ++s) names.emplace_back(sim::to_string(static_cast<sim::RunStatus>(s)));
  for (auto s : t.status) ++counts[static_cast<std::size_t>(s)];
  write_strings(stats.get(), "status_names", names);
  write_array(stats.get(), "status_counts", "1", counts.data(), counts.size());
  for (std::size_t k = 0; k < cols.f64.size(); ++k)
    write_stats_group(stats.get(), cols.f64[k]->name, cols.f64[k]->units, {calc_stats(t.f64[k], ok)}, false);
  Handle bays = make_group(stats.get(), "bays");
  std::vector<double> v(n);
  std::vector<Stats> per_bay(nb);
  for (std::size_t k = 0; k < cols.bay.size(); ++k) {
    for (std::size_t b = 0; b < nb; ++b) {
      for (std::size_t i = 0; i < n; ++i) v[i] = t.bays[k][i * nb + b];
      per_bay[b] = calc_stats(v, ok);
    }
    write_stats_group(bays.get(), cols.bay[k]->name, cols.bay[k]->units, per_bay, true);
  }
}

void write_sensitivity(hid_t file, const CampaignOptions& c, const std::vector<OutputSensitivity>& sens) {
  if (c.ensemble.sampling == SamplingMethod::saltelli) {
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

void write_timing(hid_t file, const ResultTable& t, const CampaignFileInfo& info) {
  const auto n = static_cast<std::size_t>(t.n_runs());
  Handle g = make_group(file, "timing");
  write_string_attribute(g.get(), "note", "not reproducible: depends on the machine, the ranks and the order of work");
  write_array(g.get(), "run_wall_time_s", "s", t.wall_time_s.data(), n);
  write_array(g.get(), "rank", "1", t.rank.data(), n);
  write_array(g.get(), "session", "1", t.session.data(), n);
  const ScheduleTiming& st = info.schedule;
  write_double_attribute(g.get(), "schedule_wall_s", st.wall_s);
  write_double_attribute(g.get(), "rank0_compute_s", st.rank0_compute_s);
  write_double_attribute(g.get(), "rank0_poll_s", st.rank0_poll_s);
  write_double_attribute(g.get(), "rank0_tick_s", st.rank0_tick_s);
  write_double_attribute(g.get(), "rank0_idle_s", st.rank0_idle_s);
  write_int_attribute(g.get(), "runs_by_rank0", st.runs_by_rank0);
  write_int_attribute(g.get(), "runs_by_workers", st.runs_by_workers);
  if (st.synthetic_run_cost_s >= 0) write_double_attribute(g.get(), "synthetic_run_cost_s", st.synthetic_run_cost_s);
}

void write_contents(hid_t file, const CampaignContext& ctx, const ResultTable& t, const std::vector<OutputSensitivity>& sens,
                    const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories, const CampaignFileInfo& info) {
  write_root_attributes(file, ctx, t, info);
  write_runs(file, ctx, t);
  write_stats(file, ctx, t);
  write_sensitivity(file, ctx.options, sens);
  write_histories(file, ctx.options, histories);
  write_timing(file, t, info);
  if (info.write_extra) info.write_extra(file);
}

}  // namespace

void write_campaign_h5(const std::string& path, const CampaignContext& ctx, const ResultTable& table,
                       const std::vector<OutputSensitivity>& sensitivity,
                       const std::vector<std::pair<std::int64_t, sim::RunResult>>& histories,
                       const CampaignFileInfo& info, bool force) {
  write_file_atomically(path, force, [&](hid_t file) { write_contents(file, ctx, table, sensitivity, histories, info); });
}

}  // namespace truss::campaign
