// HDF5 output of one run with the HDF5 C API. Layout: docs/hdf5-schema.md.
#include "io/h5_output.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <hdf5.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/build_info.hpp"
#include "io/h5_util.hpp"
#include "io/json_summary.hpp"
#include "io/scene_toml.hpp"


namespace truss::io {
namespace {

namespace fs = std::filesystem;
using namespace h5;
constexpr std::int64_t kSchemaVersion = 1;

void write_scalar(hid_t group, const std::string& gname, const char* name, const char* units,
                  const FieldValue& value) {
  const std::string path = fmt::format("{}/{}", gname, name);
  Handle space = scalar_space();
  if (const auto* d = std::get_if<double>(&value)) {
    Handle ds = create_dataset(group, name, H5T_IEEE_F64LE, space.get());
    check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d),
          fmt::format("write {}", path));
    write_string_attribute(ds.get(), "units", units);
  } else if (const auto* i = std::get_if<std::int64_t>(&value)) {
    Handle ds = create_dataset(group, name, H5T_STD_I64LE, space.get());
    check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, i),
          fmt::format("write {}", path));
    write_string_attribute(ds.get(), "units", units);
  } else {
    Handle type = string_type();
    Handle ds = create_dataset(group, name, type.get(), space.get());
    const char* p = std::get<std::string>(value).c_str();
    check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &p),
          fmt::format("write {}", path));
    write_string_attribute(ds.get(), "units", units);
  }
}

void write_status(hid_t summary, const sim::RunResult& r) {
  Handle type = status_enum_type();
  Handle space = scalar_space();
  Handle ds = create_dataset(summary, "status", type.get(), space.get());
  const std::int8_t v = static_cast<std::int8_t>(r.status);
  check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), "write /summary/status");
  write_string_attribute(ds.get(), "units", "1");
  write_string_attribute(ds.get(), "message", r.message);
}

void write_contents(hid_t file, const sim::RunResult& r, const std::string& scene_toml) {
  write_int_attribute(file, "schema_version", kSchemaVersion);
  write_string_attribute(file, "kind", "single_run");
  write_string_attribute(file, "scene_toml", scene_toml);
  write_string_attribute(file, "software_version", std::string(get_software_version()));
  write_string_attribute(file, "git_revision", std::string(get_git_revision()));
  write_string_attribute(file, "created_utc", utc_now_iso8601());

  {
    Handle g(H5Gcreate2(file, "summary", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
             "create group /summary");
    write_status(g.get(), r);
    for (const auto& f : run_result_fields()) write_scalar(g.get(), "/summary", f.name, f.units, f.get(r));
  }
  {
    Handle g(H5Gcreate2(file, "bays", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
             "create group /bays");
    for (const auto& f : bay_result_fields()) {
      if (std::holds_alternative<std::int64_t>(f.get(sim::BayResult{}))) {
        std::vector<std::int64_t> v;
        for (const auto& b : r.bays) v.push_back(std::get<std::int64_t>(f.get(b)));
        write_array(g.get(), f.name, f.units, v.data(), v.size());
      } else {
        std::vector<double> v;
        for (const auto& b : r.bays) v.push_back(std::get<double>(f.get(b)));
        write_array(g.get(), f.name, f.units, v.data(), v.size());
      }
    }
  }
  bool history = false;
  for (const auto& f : history_fields())
    history = history || (f.get_double ? !f.get_double(r.history)->empty()
                                       : !f.get_int(r.history)->empty());
  if (history) {
    Handle g(H5Gcreate2(file, "history", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
             "create group /history");
    write_history(g.get(), r.history);
  }
}

}  // namespace

void check_output_path(const std::string& path, bool force) {
  if (path.empty()) throw InputError("error: output file name is empty");
  std::error_code ec;
  const fs::path p(path);
  const auto st = fs::symlink_status(p, ec);
  if (fs::exists(st)) {
    if (fs::is_directory(fs::status(p, ec)))
      throw InputError(fmt::format("error: output path is a directory: {}", path));
    if (!force) throw_exists(path);
  }
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  if (!fs::is_directory(dir, ec))
    throw InputError(
        fmt::format("error: output directory does not exist: {}", dir.string()));
}

void write_run_h5(const std::string& path, const sim::RunResult& result,
                  const std::string& resolved_scene_toml, bool force) {
  check_output_path(path, force);
  write_file_atomically(path, force, [&](hid_t file) { write_contents(file, result, resolved_scene_toml); });
}

}  // namespace truss::io
