// Small RAII and writing helpers over the HDF5 C API, shared by the single-run and campaign
// writers, and the atomic, non-overwriting commit of a finished file.
#pragma once
#include <hdf5.h>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace truss::stages {
struct TimeHistory;
}
namespace truss::sim {
using stages::TimeHistory;
}

namespace truss::io::h5 {

std::string hdf5_error_text();
[[noreturn]] void throw_h5(const std::string& what);
void check(herr_t status, const std::string& what);

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

Handle scalar_space();
Handle vector_space(std::size_t n);
Handle string_type();
Handle create_group(hid_t loc, const std::string& name);
void write_string_attribute(hid_t obj, const char* name, const std::string& value);
void write_int_attribute(hid_t obj, const char* name, std::int64_t value);
void write_double_attribute(hid_t obj, const char* name, double value);
void write_doubles_attribute(hid_t obj, const char* name, const std::vector<double>& values);
// Scalar datasets and a 1-D string dataset, with their units ("1" for the strings).
void write_scalar(hid_t loc, const std::string& name, const std::string& units, double value);
void write_scalar(hid_t loc, const std::string& name, const std::string& units, std::int64_t value);
void write_strings(hid_t loc, const std::string& name, const std::vector<std::string>& values);
// A float64 / int64 dataset of rows (cols == 0) or rows x cols values, with its units.
void write_array(hid_t loc, const std::string& name, const char* units, const double* data, std::size_t rows,
                 std::size_t cols = 0);
void write_array(hid_t loc, const std::string& name, const char* units, const std::int64_t* data, std::size_t rows,
                 std::size_t cols = 0);
// One 1-D dataset per TimeHistory vector (json_summary.hpp's history_fields()) in `group`.
void write_history(hid_t group, const sim::TimeHistory& h);

// int8 enum whose members are the to_string(RunStatus) names with the RunStatus values.
Handle status_enum_type();
Handle create_dataset(hid_t loc, const std::string& path, hid_t file_type, hid_t space);

std::string utc_now_iso8601();
std::string utc_iso8601(double unix_time_s);

[[noreturn]] void throw_exists(const std::string& path);
// Flushes a finished file to disk before it is renamed into place.
void sync_file(const std::string& path);
// Renames tmp onto path; without force never replaces an existing path (InputError).
void commit(const std::string& tmp, const std::string& path, bool force);

// Creates `path` atomically: `write` fills a new HDF5 file .NAME.tmp.PID in the same directory,
// which is flushed, closed, synced and renamed onto `path` (commit()); on any error the temporary
// file is removed and the exception propagates.
void write_file_atomically(const std::string& path, bool force, const std::function<void(hid_t file)>& write);

}  // namespace truss::io::h5
