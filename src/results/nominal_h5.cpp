// /nominal of the results file (docs/hdf5-schema.md): the nominal run as a /runs row would hold it,
// with its per-bay values and history.
#include "results/campaign_file.hpp"

#include <fmt/format.h>

#include <cstring>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "io/h5_util.hpp"
#include "io/json_summary.hpp"

namespace truss::results {

using namespace io::h5;

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
  Handle g = create_group(nominal, "bays");
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
  Handle g = create_group(file, "nominal");
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
  Handle h = create_group(g.get(), "history");
  write_history(h.get(), r.history);
}

}  // namespace truss::results
