// Reading the finished /runs back (campaign/result_store.hpp): columns for the Sobol' indices,
// the end summary and the statistics a streamed window could not resolve.
#include <algorithm>

#include "campaign/result_store.hpp"

namespace truss::campaign {

using namespace io::h5;

std::vector<double> read_f64_column(hid_t file, const std::string& path, std::int64_t n) {
  std::vector<double> v(static_cast<std::size_t>(n));
  if (n == 0) return v;
  Handle ds(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose, "open " + path);
  check(H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "read " + path);
  return v;
}

std::vector<std::vector<double>> read_f64_columns(hid_t file, const std::string& path, std::int64_t n, std::int64_t width,
                                                  std::int64_t col0, std::int64_t cols, std::int64_t block_rows) {
  std::vector<std::vector<double>> out(static_cast<std::size_t>(cols), std::vector<double>(static_cast<std::size_t>(n)));
  if (n == 0) return out;
  Handle ds(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose, "open " + path);
  Handle fspace(H5Dget_space(ds.get()), H5Sclose, "space of " + path);
  std::vector<double> buf(static_cast<std::size_t>(block_rows * width));
  for (std::int64_t first = 0; first < n; first += block_rows) {
    const std::int64_t rows = std::min(block_rows, n - first);
    const hsize_t start[2] = {static_cast<hsize_t>(first), 0}, count[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(width)};
    check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select " + path);
    Handle mspace(H5Screate_simple(2, count, nullptr), H5Sclose, "memory space of " + path);
    check(H5Dread(ds.get(), H5T_NATIVE_DOUBLE, mspace.get(), fspace.get(), H5P_DEFAULT, buf.data()), "read " + path);
    for (std::int64_t i = 0; i < rows; ++i)
      for (std::int64_t j = 0; j < cols; ++j)
        out[static_cast<std::size_t>(j)][static_cast<std::size_t>(first + i)] = buf[static_cast<std::size_t>(i * width + col0 + j)];
  }
  return out;
}

std::vector<std::int8_t> read_status(hid_t file, std::int64_t n) {
  std::vector<std::int8_t> v(static_cast<std::size_t>(n), 0);
  if (n == 0) return v;
  Handle ds(H5Dopen2(file, "runs/status", H5P_DEFAULT), H5Dclose, "open /runs/status");
  Handle type = status_enum_type();  // enum to enum: HDF5 does not convert an enum to an integer
  check(H5Dread(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "read /runs/status");
  return v;
}

std::string read_message(hid_t file, std::int64_t run) {
  Handle ds(H5Dopen2(file, "runs/message", H5P_DEFAULT), H5Dclose, "open /runs/message");
  Handle fspace(H5Dget_space(ds.get()), H5Sclose, "space of /runs/message");
  const hsize_t start[1] = {static_cast<hsize_t>(run)}, count[1] = {1};
  check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select /runs/message");
  Handle mspace(H5Screate_simple(1, count, nullptr), H5Sclose, "memory space of /runs/message");
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose, "string type");
  check(H5Tset_size(type.get(), H5T_VARIABLE), "variable string type");
  char* text = nullptr;
  check(H5Dread(ds.get(), type.get(), mspace.get(), fspace.get(), H5P_DEFAULT, &text), "read /runs/message");
  std::string s = text ? text : "";
  H5free_memory(text);
  return s;
}

}  // namespace truss::campaign
