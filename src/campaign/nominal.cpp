#include "campaign/nominal.hpp"

#include <fmt/format.h>

#include <cstring>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "io/h5_util.hpp"
#include "io/json_summary.hpp"
#include "sim/scene.hpp"
#include "sim/simulate.hpp"

namespace truss::campaign {

using namespace io::h5;

sim::RunResult calc_nominal_run(const CampaignOptions& c, double step_s) {
  sim::SceneOptions scene = c.base;
  scene.run.max_wall_time_s = c.ensemble.max_run_wall_time_s;
  scene.run.output_step_s = step_s;
  try {
    return sim::simulate(scene, sim::build_mast(scene));
  } catch (const std::exception& e) {
    sim::RunResult r;
    r.status = sim::RunStatus::invalid_input;
    r.message = fmt::format("nominal run: {}", e.what());
    return r;
  }
}

namespace {

void write_field(hid_t g, const io::RunField& f, const sim::RunResult& r) {
  const io::FieldValue v = f.get(r);
  Handle space = scalar_space();
  const std::string what = fmt::format("write /nominal/{}", f.name);
  if (const auto* d = std::get_if<double>(&v)) {
    Handle ds = create_dataset(g, f.name, H5T_IEEE_F64LE, space.get());
    check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d), what);
    write_string_attribute(ds.get(), "units", f.units);
  } else if (const auto* i = std::get_if<std::int64_t>(&v)) {
    Handle ds = create_dataset(g, f.name, H5T_STD_I64LE, space.get());
    check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, i), what);
    write_string_attribute(ds.get(), "units", f.units);
  } else {
    Handle type = string_type();
    Handle ds = create_dataset(g, f.name, type.get(), space.get());
    const char* p = std::get<std::string>(v).c_str();
    check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p), what);
    write_string_attribute(ds.get(), "units", f.units);
  }
}

void write_bays(hid_t nominal, const sim::RunResult& r, int n_bays_max) {
  Handle g(H5Gcreate2(nominal, "bays", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create group /nominal/bays");
  const auto nb = static_cast<std::size_t>(n_bays_max);
  for (const auto& f : io::bay_result_fields()) {
    if (!std::holds_alternative<double>(f.get(sim::BayResult{}))) continue;  // bay: the column index
    std::vector<double> v(nb, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t b = 0; b < std::min(nb, r.bays.size()); ++b) v[b] = std::get<double>(f.get(r.bays[b]));
    write_array(g.get(), f.name, f.units, v.data(), nb);
  }
}

}  // namespace

void write_nominal_group(hid_t file, const sim::RunResult& r, int n_bays_max) {
  Handle g(H5Gcreate2(file, "nominal", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create group /nominal");
  write_string_attribute(g.get(), "description",
                         "the base scene without dispersions, computed once on rank 0 (docs/hdf5-schema.md)");
  {
    Handle type = status_enum_type();
    Handle space = scalar_space();
    Handle ds = create_dataset(g.get(), "status", type.get(), space.get());
    const auto v = static_cast<std::int8_t>(r.status);
    check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), "write /nominal/status");
    write_string_attribute(ds.get(), "units", "1");
    write_string_attribute(ds.get(), "message", r.message);
  }
  for (const auto& f : io::run_result_fields())
    if (std::strcmp(f.name, "wall_time_s") != 0) write_field(g.get(), f, r);
  write_bays(g.get(), r, n_bays_max);
  Handle h(H5Gcreate2(g.get(), "history", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create group /nominal/history");
  write_history(h.get(), r.history);
}

}  // namespace truss::campaign
