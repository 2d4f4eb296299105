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

#include "io/json_summary.hpp"
#include "io/scene_toml.hpp"


namespace truss::io {
namespace {

namespace fs = std::filesystem;
constexpr std::int64_t kSchemaVersion = 1;

// ---------------------------------------------------------------------------------------------
// Errors

herr_t collect_error(unsigned, const H5E_error2_t* err, void* data) {
  auto* out = static_cast<std::vector<std::string>*>(data);
  if (err && err->desc && *err->desc) out->emplace_back(err->desc);
  return 0;
}

// The current HDF5 error stack as one line: the outermost and innermost descriptions.
std::string hdf5_error_text() {
  std::vector<std::string> descs;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect_error, &descs);
  H5Eclear2(H5E_DEFAULT);
  if (descs.empty()) return "unknown HDF5 error";
  if (descs.size() == 1 || descs.front() == descs.back()) return descs.front();
  return descs.front() + " (" + descs.back() + ")";
}

[[noreturn]] void throw_h5(const std::string& what) {
  throw std::runtime_error(fmt::format("HDF5 error: {}: {}", what, hdf5_error_text()));
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw_h5(what);
}

// Owns one HDF5 identifier.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t), const std::string& what) : id_(id), close_(close) {
    if (id_ < 0) throw_h5(what);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  Handle& operator=(Handle&&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  void close(const std::string& what) {
    const herr_t s = close_(id_);
    id_ = -1;
    check(s, what);
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// ---------------------------------------------------------------------------------------------
// Writers

Handle scalar_space() { return Handle(H5Screate(H5S_SCALAR), H5Sclose, "create scalar dataspace"); }

Handle vector_space(std::size_t n) {
  const hsize_t dims[1] = {static_cast<hsize_t>(n)};
  return Handle(H5Screate_simple(1, dims, nullptr), H5Sclose, "create 1-D dataspace");
}

Handle string_type() {
  Handle t(H5Tcopy(H5T_C_S1), H5Tclose, "copy string type");
  check(H5Tset_size(t.get(), H5T_VARIABLE), "set string size");
  check(H5Tset_cset(t.get(), H5T_CSET_UTF8), "set string character set");
  return t;
}

void write_string_attribute(hid_t obj, const char* name, const std::string& value) {
  Handle type = string_type();
  Handle space = scalar_space();
  Handle attr(H5Acreate2(obj, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
              fmt::format("create attribute {}", name));
  const char* p = value.c_str();
  check(H5Awrite(attr.get(), type.get(), &p), fmt::format("write attribute {}", name));
}

void write_int_attribute(hid_t obj, const char* name, std::int64_t value) {
  Handle space = scalar_space();
  Handle attr(H5Acreate2(obj, name, H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT),
              H5Aclose, fmt::format("create attribute {}", name));
  check(H5Awrite(attr.get(), H5T_NATIVE_INT64, &value), fmt::format("write attribute {}", name));
}

Handle create_dataset(hid_t loc, const std::string& path, hid_t file_type, hid_t space) {
  return Handle(H5Dcreate2(loc, path.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT,
                           H5P_DEFAULT),
                H5Dclose, fmt::format("create dataset {}", path));
}

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

void write_vector(hid_t group, const std::string& gname, const char* name, const char* units,
                  const double* data, std::size_t n) {
  Handle space = vector_space(n);
  Handle ds = create_dataset(group, name, H5T_IEEE_F64LE, space.get());
  if (n > 0)
    check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
          fmt::format("write {}/{}", gname, name));
  write_string_attribute(ds.get(), "units", units);
}

void write_vector(hid_t group, const std::string& gname, const char* name, const char* units,
                  const std::int64_t* data, std::size_t n) {
  Handle space = vector_space(n);
  Handle ds = create_dataset(group, name, H5T_STD_I64LE, space.get());
  if (n > 0)
    check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
          fmt::format("write {}/{}", gname, name));
  write_string_attribute(ds.get(), "units", units);
}

void write_status(hid_t summary, const sim::RunResult& r) {
  Handle type(H5Tenum_create(H5T_NATIVE_INT8), H5Tclose, "create status enum type");
  for (int i = 0; i < sim::kRunStatusCount; ++i) {
    const std::int8_t v = static_cast<std::int8_t>(i);
    const char* name = sim::to_string(static_cast<sim::RunStatus>(i));
    check(H5Tenum_insert(type.get(), name, &v), fmt::format("add status name '{}'", name));
  }
  Handle space = scalar_space();
  Handle ds = create_dataset(summary, "status", type.get(), space.get());
  const std::int8_t v = static_cast<std::int8_t>(r.status);
  check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), "write /summary/status");
  write_string_attribute(ds.get(), "units", "1");
  write_string_attribute(ds.get(), "message", r.message);
}

std::string utc_now_iso8601() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

void write_contents(hid_t file, const sim::RunResult& r, const std::string& scene_toml) {
  write_int_attribute(file, "schema_version", kSchemaVersion);
  write_string_attribute(file, "kind", "single_run");
  write_string_attribute(file, "scene_toml", scene_toml);
  write_string_attribute(file, "software_version", TRUSS_VERSION);
  write_string_attribute(file, "git_revision", TRUSS_GIT_REV);
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
        write_vector(g.get(), "/bays", f.name, f.units, v.data(), v.size());
      } else {
        std::vector<double> v;
        for (const auto& b : r.bays) v.push_back(std::get<double>(f.get(b)));
        write_vector(g.get(), "/bays", f.name, f.units, v.data(), v.size());
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
    for (const auto& f : history_fields()) {
      if (f.get_double) {
        const auto& v = *f.get_double(r.history);
        write_vector(g.get(), "/history", f.name, f.units, v.data(), v.size());
      } else {
        const auto& v = *f.get_int(r.history);
        const std::vector<std::int64_t> w(v.begin(), v.end());
        write_vector(g.get(), "/history", f.name, f.units, w.data(), w.size());
      }
    }
  }
}

[[noreturn]] void throw_exists(const std::string& path) {
  throw InputError(fmt::format("error: output file exists: {} (use --force to overwrite)", path));
}

// Flushes a finished file to disk before it is renamed into place.
void sync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(fmt::format("cannot reopen {}: {}", path, std::strerror(errno)));
  const int rc = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (rc != 0) throw std::runtime_error(fmt::format("cannot sync {}: {}", path, std::strerror(err)));
}

// Renames tmp onto path; without force never replaces an existing path.
void commit(const std::string& tmp, const std::string& path, bool force) {
  if (force) {
    if (std::rename(tmp.c_str(), path.c_str()) != 0)
      throw std::runtime_error(
          fmt::format("cannot rename {} to {}: {}", tmp, path, std::strerror(errno)));
    return;
  }
#ifdef RENAME_NOREPLACE
  if (::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, path.c_str(), RENAME_NOREPLACE) == 0) return;
  if (errno == EEXIST) throw_exists(path);
  if (errno != EINVAL && errno != ENOSYS && errno != ENOTSUP)
    throw std::runtime_error(
        fmt::format("cannot rename {} to {}: {}", tmp, path, std::strerror(errno)));
#endif
  // No renameat2 here: a hard link fails when the target exists.
  if (::link(tmp.c_str(), path.c_str()) == 0) {
    ::unlink(tmp.c_str());
    return;
  }
  if (errno == EEXIST) throw_exists(path);
  // No hard links on this file system either: check, then rename (small race window).
  std::error_code ec;
  if (fs::exists(fs::symlink_status(path, ec))) throw_exists(path);
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw std::runtime_error(
        fmt::format("cannot rename {} to {}: {}", tmp, path, std::strerror(errno)));
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
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through exceptions

  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path();
  const std::string tmp =
      (dir / fmt::format(".{}.tmp.{}", p.filename().string(), static_cast<long>(::getpid())))
          .string();
  try {
    {
      Handle file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose,
                  fmt::format("create {}", tmp));
      write_contents(file.get(), result, resolved_scene_toml);
      check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), fmt::format("flush {}", tmp));
      file.close(fmt::format("close {}", tmp));
    }
    sync_file(tmp);
    commit(tmp, path, force);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

}  // namespace truss::io
