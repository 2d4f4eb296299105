// Reading the finished /runs back (result_store.hpp): columns for the Sobol' indices and the
// statistics a streamed window could not resolve (on rank 0, or by any rank from the stored chunks'
// places: read_back.hpp), rows for subset simulation's failure samples; chunk by chunk through the
// results' codec.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

#include "results/chunk_codec.hpp"
#include "results/read_back.hpp"
#include "results/result_store.hpp"

namespace truss::results {

using namespace io::h5;

namespace {

// A float64 dataset of /runs read chunk by chunk as stored (H5Dread_chunk) and decoded by the
// results' own codec (ChunkCodec::decode: ISA-L's inflate, about twice as fast as HDF5's zlib
// filter on these chunks, docs/benchmarks.md "The end of a sweep"). Its pipeline is shuffle +
// deflate or empty, as the store creates it.
class ChunkReader {
 public:
  ChunkReader(hid_t file, const std::string& path)
      : path_(path), ds_(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose, "open " + path) {
    Handle dcpl(H5Dget_create_plist(ds_.get()), H5Pclose, "creation list of " + path);
    Handle space(H5Dget_space(ds_.get()), H5Sclose, "space of " + path);
    const int rank = H5Sget_simple_extent_ndims(space.get());
    hsize_t dims[2] = {0, 1}, chunk[2] = {0, 1};
    Handle type(H5Dget_type(ds_.get()), H5Tclose, "type of " + path);
    H5Sget_simple_extent_dims(space.get(), dims, nullptr);
    if (rank < 1 || rank > 2 || H5Pget_chunk(dcpl.get(), rank, chunk) != rank || chunk[1] != dims[1] ||
        H5Tequal(type.get(), H5T_NATIVE_DOUBLE) <= 0)
      throw std::runtime_error(path + ": not a float64 dataset in chunks of whole rows");
    n_rows_ = static_cast<std::int64_t>(dims[0]);
    chunk_rows_ = static_cast<std::int64_t>(chunk[0]);
    width_ = static_cast<std::int64_t>(chunk[1]);
    const int nf = H5Pget_nfilters(dcpl.get());
    auto filter = [&](unsigned k) {
      unsigned flags = 0;
      std::size_t n_values = 0;  // the filter's parameters are not read
      return H5Pget_filter2(dcpl.get(), k, &flags, &n_values, nullptr, 0, nullptr, nullptr);
    };
    filtered_ = nf == 2;
    if (!(nf == 0 || (filtered_ && filter(0) == H5Z_FILTER_SHUFFLE && filter(1) == H5Z_FILTER_DEFLATE)))
      throw std::runtime_error(path + ": a filter pipeline other than shuffle + deflate");
  }
  std::int64_t n_rows() const { return n_rows_; }
  std::int64_t chunk_rows() const { return chunk_rows_; }
  std::int64_t width() const { return width_; }
  bool filtered() const { return filtered_; }
  // Where the chunk whose first row is `first` is stored (its bytes are read by any process).
  ReadBackJob::Chunk find_stored(std::int64_t first) const {
    const hsize_t offset[2] = {static_cast<hsize_t>(first), 0};
    unsigned mask = 0;
    haddr_t addr = HADDR_UNDEF;
    hsize_t nbytes = 0;
    check(H5Dget_chunk_info_by_coord(ds_.get(), offset, &mask, &addr, &nbytes), "where a chunk of " + path_ + " is");
    if (addr == HADDR_UNDEF || nbytes == 0)
      throw std::runtime_error(fmt::format("{}: the chunk at row {} is not stored", path_, first));
    return {static_cast<std::uint64_t>(addr), static_cast<std::uint64_t>(nbytes), mask};
  }
  // The chunk whose first row is `first`, chunk_rows x width doubles.
  const double* read(std::int64_t first) {
    const hsize_t offset[2] = {static_cast<hsize_t>(first), 0};
    hsize_t nbytes = 0;
    check(H5Dget_chunk_storage_size(ds_.get(), offset, &nbytes), "size of a chunk of " + path_);
    if (nbytes == 0) throw std::runtime_error(fmt::format("{}: the chunk at row {} is not stored", path_, first));
    stored_.resize(nbytes);
    std::uint32_t mask = 0;
    check(H5Dread_chunk(ds_.get(), H5P_DEFAULT, offset, &mask, stored_.data()), "read a chunk of " + path_);
    const auto raw_bytes = static_cast<std::size_t>(chunk_rows_ * width_) * sizeof(double);
    codec_.decode(stored_, mask, filtered_, sizeof(double), raw_bytes, raw_);
    return reinterpret_cast<const double*>(raw_.data());
  }

 private:
  std::string path_;
  Handle ds_;
  std::int64_t n_rows_ = 0, chunk_rows_ = 0, width_ = 1;
  bool filtered_ = false;
  std::string stored_, raw_;
  ChunkCodec codec_;
};

}  // namespace

std::vector<double> read_f64_column(hid_t file, const std::string& path, std::int64_t n) {
  return std::move(read_f64_columns(file, path, n, 0, 1).front());
}

std::vector<std::vector<double>> read_f64_columns(hid_t file, const std::string& path, std::int64_t n,
                                                  std::int64_t col0, std::int64_t cols) {
  std::vector<std::vector<double>> out(static_cast<std::size_t>(cols),
                                       std::vector<double>(static_cast<std::size_t>(n)));
  if (n == 0) return out;
  ChunkReader reader(file, path);
  const std::int64_t width = reader.width();
  if (col0 < 0 || cols < 1 || col0 + cols > width || n > reader.n_rows())
    throw std::out_of_range(fmt::format("{}: columns {} to {} of {}, {} rows of {}", path, col0, col0 + cols - 1, width,
                                        n, reader.n_rows()));
  for (std::int64_t first = 0; first < n; first += reader.chunk_rows()) {
    const double* chunk = reader.read(first);
    const std::int64_t rows = std::min(reader.chunk_rows(), n - first);
    for (std::int64_t i = 0; i < rows; ++i)
      for (std::int64_t j = 0; j < cols; ++j)
        out[static_cast<std::size_t>(j)][static_cast<std::size_t>(first + i)] = chunk[i * width + col0 + j];
  }
  return out;
}

std::vector<double> read_f64_rows(hid_t file, const std::string& path, const std::vector<std::int64_t>& rows) {
  ChunkReader reader(file, path);
  const std::int64_t width = reader.width();
  std::vector<double> out(rows.size() * static_cast<std::size_t>(width));
  // The rows in row order (each chunk decoded once), each copied to its place in `rows`' order.
  std::vector<std::size_t> order(rows.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return rows[a] < rows[b]; });
  std::int64_t first = -1;
  const double* chunk = nullptr;
  for (const std::size_t k : order) {
    const std::int64_t r = rows[k];
    if (r < 0 || r >= reader.n_rows())
      throw std::out_of_range(fmt::format("{}: row {} of {}", path, r, reader.n_rows()));
    const std::int64_t at = r - r % reader.chunk_rows();
    if (at != first) chunk = reader.read(first = at);
    std::copy_n(chunk + (r - at) * width, width, out.data() + k * static_cast<std::size_t>(width));
  }
  return out;
}

namespace {

// A dataset's job: its chunks' places and the columns not yet resolved (resolved[c] == 0).
void add_job(hid_t file, const std::string& path, std::int64_t n, std::int32_t group, std::int64_t first_index,
             const std::vector<std::uint8_t>& resolved, std::vector<ReadBackJob>& jobs) {
  if (std::all_of(resolved.begin(), resolved.end(), [](std::uint8_t r) { return r != 0; })) return;
  ChunkReader reader(file, path);
  ReadBackJob job;
  job.path = path;
  job.rows = n;
  job.chunk_rows = reader.chunk_rows();
  job.width = reader.width();
  job.filtered = reader.filtered();
  if (n > reader.n_rows() || static_cast<std::int64_t>(resolved.size()) != reader.width())
    throw std::out_of_range(fmt::format("{}: {} columns of {}, {} rows of {}", path, resolved.size(), reader.width(), n,
                                        reader.n_rows()));
  for (std::int64_t first = 0; first < n; first += reader.chunk_rows()) job.chunks.push_back(reader.find_stored(first));
  for (std::size_t c = 0; c < resolved.size(); ++c)
    if (!resolved[c])
      job.columns.push_back({static_cast<std::int64_t>(c), group, first_index + static_cast<std::int64_t>(c)});
  jobs.push_back(std::move(job));
}

}  // namespace

std::vector<ReadBackJob> find_read_back(hid_t file, const campaign::RecordLayout& layout, const StreamedStats& s,
                                        std::int64_t n) {
  std::vector<ReadBackJob> jobs;
  if (n == 0) return jobs;
  std::size_t k = 0, j = 0;  // the k-th float64 output, the j-th per-bay one
  for (const campaign::Field& f : layout.fields()) {
    if (!f.statistics) continue;
    const std::string path = std::string(campaign::group_path(f.group)) + "/" + f.name;
    if (f.scale == campaign::Scale::none) {
      add_job(file, path, n, -1, static_cast<std::int64_t>(k), {s.f64_resolved.at(k)}, jobs);
      ++k;
    } else {
      add_job(file, path, n, static_cast<std::int32_t>(j), 0, s.bays_resolved.at(j), jobs);
      ++j;
    }
  }
  return jobs;
}

std::vector<ReadBackAnswer> calc_read_back(const std::string& path, const ReadBackJob& job,
                                           const std::vector<std::uint8_t>& ok, std::size_t group) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(fmt::format("{}: {}", path, std::strerror(errno)));
  std::string stored, raw;
  ChunkCodec codec;
  const auto raw_bytes = static_cast<std::size_t>(job.chunk_rows * job.width) * sizeof(double);
  // Columns [j0, j1) of the job: one pass over the chunks, each decoded once.
  auto read_columns = [&](std::size_t j0, std::size_t j1) {
    std::vector<std::vector<double>> cols(j1 - j0, std::vector<double>(static_cast<std::size_t>(job.rows)));
    for (std::size_t c = 0; c < job.chunks.size(); ++c) {
      const ReadBackJob::Chunk& at = job.chunks[c];
      stored.resize(at.bytes);
      if (::pread(fd, stored.data(), at.bytes, static_cast<off_t>(at.offset)) != static_cast<ssize_t>(at.bytes))
        throw std::runtime_error(fmt::format("{}: a chunk of {} at byte {} cannot be read", path, job.path, at.offset));
      codec.decode(stored, at.mask, job.filtered, sizeof(double), raw_bytes, raw);
      const auto* v = reinterpret_cast<const double*>(raw.data());
      const std::int64_t first = static_cast<std::int64_t>(c) * job.chunk_rows;
      const std::int64_t rows = std::min(job.chunk_rows, job.rows - first);
      for (std::size_t j = j0; j < j1; ++j)
        for (std::int64_t i = 0; i < rows; ++i)
          cols[j - j0][static_cast<std::size_t>(first + i)] = v[i * job.width + job.columns[j].column];
    }
    return cols;
  };
  if (group == 0) group = static_cast<std::size_t>(find_read_back_group(job.rows));
  std::vector<ReadBackAnswer> out;
  try {
    for (std::size_t j0 = 0; j0 < job.columns.size(); j0 += group) {
      const std::size_t j1 = std::min(job.columns.size(), j0 + group);
      const std::vector<std::vector<double>> cols = read_columns(j0, j1);
      for (std::size_t j = j0; j < j1; ++j)
        out.push_back(
            {job.columns[j].group, job.columns[j].index, statistics::calc_stats(cols[j - j0], ok).percentiles});
    }
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
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
  const Handle type = string_type();
  char* text = nullptr;
  check(H5Dread(ds.get(), type.get(), mspace.get(), fspace.get(), H5P_DEFAULT, &text), "read /runs/message");
  std::string s = text ? text : "";
  H5free_memory(text);
  return s;
}

}  // namespace truss::results
