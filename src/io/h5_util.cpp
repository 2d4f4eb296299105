#include "io/h5_util.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include <unistd.h>

#include "io/scene_toml.hpp"
#include "io/json_summary.hpp"
#include "sim/result.hpp"

namespace truss::io::h5 {

namespace fs = std::filesystem;

namespace {
herr_t collect_error(unsigned, const H5E_error2_t* err, void* data) {
  auto* out = static_cast<std::vector<std::string>*>(data);
  if (err && err->desc && *err->desc) out->emplace_back(err->desc);
  return 0;
}
}  // namespace

// ---------------------------------------------------------------------------------------------
// Errors


// The current HDF5 error stack as one line: the outermost and innermost descriptions.
std::string hdf5_error_text() {
  std::vector<std::string> descs;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect_error, &descs);
  H5Eclear2(H5E_DEFAULT);
  if (descs.empty()) return "unknown HDF5 error";
  // A failed system call: HDF5's innermost description spans lines and quotes the system's
  // message ("... errno = 28, error message = 'No space left on device', buf = ..."): keep that.
  for (auto& d : descs) {
    const auto at = d.find("error message = '");
    if (at == std::string::npos) continue;
    const auto from = at + 17, to = d.find('\'', from);
    d = d.substr(0, d.find(':')) + ": " + d.substr(from, to == std::string::npos ? std::string::npos : to - from);
  }
  if (descs.size() == 1 || descs.front() == descs.back()) return descs.front();
  return descs.front() + " (" + descs.back() + ")";
}

[[noreturn]] void throw_h5(const std::string& what) {
  throw std::runtime_error(fmt::format("HDF5 error: {}: {}", what, hdf5_error_text()));
}

void check(herr_t status, const std::string& what) {
  if (status < 0) throw_h5(what);
}


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

Handle create_group(hid_t loc, const std::string& name) {
  return Handle(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                "create group " + name);
}

namespace {
void write_f64_attribute(hid_t obj, const char* name, hid_t space, const double* values) {
  Handle attr(H5Acreate2(obj, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
              fmt::format("create attribute {}", name));
  if (values) check(H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, values), fmt::format("write attribute {}", name));
}
}  // namespace

void write_double_attribute(hid_t obj, const char* name, double value) {
  write_f64_attribute(obj, name, scalar_space().get(), &value);
}

void write_doubles_attribute(hid_t obj, const char* name, const std::vector<double>& values) {
  write_f64_attribute(obj, name, vector_space(values.size()).get(), values.empty() ? nullptr : values.data());
}

void write_scalar(hid_t loc, const std::string& name, const std::string& units, double value) {
  Handle space = scalar_space();
  Handle ds = create_dataset(loc, name, H5T_IEEE_F64LE, space.get());
  check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &value), "write " + name);
  write_string_attribute(ds.get(), "units", units);
}

void write_scalar(hid_t loc, const std::string& name, const std::string& units, std::int64_t value) {
  Handle space = scalar_space();
  Handle ds = create_dataset(loc, name, H5T_STD_I64LE, space.get());
  check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &value), "write " + name);
  write_string_attribute(ds.get(), "units", units);
}

void write_strings(hid_t loc, const std::string& name, const std::vector<std::string>& values) {
  Handle type = string_type();
  Handle space = vector_space(values.size());
  Handle ds = create_dataset(loc, name, type.get(), space.get());
  std::vector<const char*> p;
  for (const auto& s : values) p.push_back(s.c_str());
  if (!p.empty()) check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()), "write " + name);
  write_string_attribute(ds.get(), "units", "1");
}

Handle create_dataset(hid_t loc, const std::string& path, hid_t file_type, hid_t space) {
  return Handle(H5Dcreate2(loc, path.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT,
                           H5P_DEFAULT),
                H5Dclose, fmt::format("create dataset {}", path));
}

namespace {
void write_array_of(hid_t loc, const std::string& name, const char* units, const void* data, hid_t file_type,
                    hid_t mem_type, std::size_t rows, std::size_t cols) {
  const hsize_t dims[2] = {rows, cols};
  Handle space(H5Screate_simple(cols ? 2 : 1, dims, nullptr), H5Sclose, "create dataspace for " + name);
  Handle ds = create_dataset(loc, name, file_type, space.get());
  if (rows > 0) check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write " + name);
  write_string_attribute(ds.get(), "units", units);
}
}  // namespace

void write_array(hid_t loc, const std::string& name, const char* units, const double* data, std::size_t rows,
                 std::size_t cols) {
  write_array_of(loc, name, units, data, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, rows, cols);
}

void write_array(hid_t loc, const std::string& name, const char* units, const std::int64_t* data, std::size_t rows,
                 std::size_t cols) {
  write_array_of(loc, name, units, data, H5T_STD_I64LE, H5T_NATIVE_INT64, rows, cols);
}

void write_history(hid_t group, const sim::TimeHistory& h) {
  for (const auto& f : history_fields()) {
    if (f.get_double) {
      const auto& v = *f.get_double(h);
      write_array(group, f.name, f.units, v.data(), v.size());
    } else {
      const auto& v = *f.get_int(h);
      const std::vector<std::int64_t> w(v.begin(), v.end());
      write_array(group, f.name, f.units, w.data(), w.size());
    }
  }
  // Free stack: the heights of frames 0..n, one row per sample (rows x (n + 1)).
  if (h.n_frames > 0 && !h.frame_height_m.empty())
    write_array(group, "frame_height_m", "m", h.frame_height_m.data(), h.frame_height_m.size() / static_cast<std::size_t>(h.n_frames),
                static_cast<std::size_t>(h.n_frames));
}

Handle status_enum_type() {
  Handle type(H5Tenum_create(H5T_NATIVE_INT8), H5Tclose, "create status enum type");
  for (int i = 0; i < sim::kRunStatusCount; ++i) {
    const std::int8_t v = static_cast<std::int8_t>(i);
    const char* name = sim::to_string(static_cast<sim::RunStatus>(i));
    check(H5Tenum_insert(type.get(), name, &v), fmt::format("add status name '{}'", name));
  }
  return type;
}

std::string utc_now_iso8601() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string utc_iso8601(double unix_time_s) {
  const std::time_t t = static_cast<std::time_t>(std::floor(unix_time_s));
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
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

void write_file_atomically(const std::string& path, bool force, const std::function<void(hid_t file)>& write) {
  // A write that fails (disk full) makes H5Fclose fail too, and HDF5 1.10 then keeps a file
  // identifier whose structure is half torn down: its exit-time cleanup (H5_term_library, an
  // atexit handler) crashes on it (SIGSEGV in H5F__close_cb). Every identifier we open is closed
  // by its Handle, the temporary file is removed below, and the process frees the rest at exit,
  // so the library's atexit cleanup is not needed: switch it off. This must precede the first
  // HDF5 call of the process (it is a no-op after); both commands make no HDF5 call before this.
  H5dont_atexit();
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported through exceptions
  const fs::path p(path);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path();
  const std::string tmp = (dir / fmt::format(".{}.tmp.{}", p.filename().string(), static_cast<long>(::getpid()))).string();
  try {
    {
      Handle file(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, "create " + tmp);
      write(file.get());
      check(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "flush " + tmp);
      file.close("close " + tmp);
    }
    sync_file(tmp);
    commit(tmp, path, force);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

}  // namespace truss::io::h5
