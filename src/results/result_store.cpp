#include "results/result_store.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>
#include <hdf5_hl.h>


namespace truss::results {

using namespace io::h5;
using campaign::Field;
using campaign::RecordLayout;
using campaign::Scale;
using campaign::ValueType;

// One per-run dataset (ds_: the fields', /runs/message, /timing/session: the file's order).
struct ResultStore::Dataset {
  Handle ds;
  std::size_t width = 1;
};

namespace {

// An extendible dataset of rows (x width columns when `two_d`), no rows yet, chunks of `chunk`
// whole rows: a chunk of runs is one contiguous block of each dataset. Byte shuffle then deflate
// for numbers, deflate for strings: pure functions of a chunk's values, so the stored values, and
// each chunk's bytes, do not depend on the ranks or the order in which runs finished.
Handle make_dataset(hid_t loc, const std::string& name, hid_t type, const std::string& units, bool two_d,
                    std::int64_t width, std::int64_t chunk, int deflate) {
  const hsize_t dims[2] = {0, static_cast<hsize_t>(width)};
  const hsize_t maxdims[2] = {H5S_UNLIMITED, static_cast<hsize_t>(width)};
  Handle space(H5Screate_simple(two_d ? 2 : 1, dims, maxdims), H5Sclose, "dataspace for " + name);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "dataset properties for " + name);
  const hsize_t cdims[2] = {static_cast<hsize_t>(chunk), static_cast<hsize_t>(width)};
  check(H5Pset_chunk(dcpl.get(), two_d ? 2 : 1, cdims), "chunk " + name);
  if (deflate > 0 && H5Tis_variable_str(type) <= 0) check(H5Pset_shuffle(dcpl.get()), "shuffle " + name);
  if (deflate > 0) check(H5Pset_deflate(dcpl.get(), static_cast<unsigned>(deflate)), "deflate " + name);
  Handle ds(H5Dcreate2(loc, name.c_str(), type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT), H5Dclose,
            "create dataset " + name);
  write_string_attribute(ds.get(), "units", units);
  return ds;
}

// A dimension scale: values first .. first + n - 1, named `name` (xarray's dimension name).
Handle make_scale(hid_t loc, const std::string& name, std::int64_t first, std::int64_t n) {
  std::vector<std::int64_t> v(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) v[static_cast<std::size_t>(i)] = first + i;
  write_array(loc, name, "1", v.data(), v.size());
  Handle ds(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose, "open " + name);
  check(H5DSset_scale(ds.get(), name.c_str()), "make " + name + " a dimension scale");
  return ds;
}

}  // namespace

ResultStore::ResultStore(hid_t file, PlacementState& placement, const campaign::RecordLayout& layout,
                         const StoreOptions& opts)
    : L_(layout), placement_(placement), cols_(layout), chunk_(opts.chunk_runs) {
  if (const std::string e = opts.validate(); !e.empty()) throw std::invalid_argument("result store: " + e);
  create_datasets(file, opts.deflate_level);
}

ResultStore::~ResultStore() = default;

// Every field's dataset in its group, then the message and the session (the file's order); dimension
// scales, so that netCDF-4 readers (xarray) see named dimensions: /runs/run_index on the rows of
// every per-run dataset, /bay (1..n_bays_max) and /frame (0..n_bays_max) on the columns of the
// per-bay and per-frame ones.
void ResultStore::create_datasets(hid_t file, int deflate) {
  for (const char* g : {"runs", "runs/bays", "runs/inputs", "timing"}) groups_.push_back(create_group(file, g));
  const Handle status_type = status_enum_type(), str_type = string_type();
  const auto& fields = L_.fields();
  for (const Field& fd : fields) {
    const hid_t type = fd.type == ValueType::status ? status_type.get()
                       : fd.type == ValueType::i64  ? H5T_STD_I64LE
                                                    : H5T_IEEE_F64LE;
    ds_.push_back({make_dataset(groups_[static_cast<std::size_t>(fd.group)].get(), fd.name, type, fd.units,
                                fd.scale != Scale::none, fd.width, chunk_, deflate),
                   static_cast<std::size_t>(fd.width)});
  }
  ds_.push_back({make_dataset(groups_[0].get(), "message", str_type.get(), "1", false, 1, chunk_, deflate), 1});
  ds_.push_back({make_dataset(groups_[3].get(), "session", H5T_STD_I64LE, "1", false, 1, chunk_, deflate), 1});
  const hid_t run = ds_[RecordLayout::kRun].ds.get();
  check(H5DSset_scale(run, "run_index"), "make /runs/run_index a dimension scale");
  const Handle bay = make_scale(file, "bay", 1, L_.n_bays_max());
  std::unique_ptr<Handle> frame;
  for (const Field& fd : fields)
    if (fd.scale == Scale::frame && !frame)
      frame = std::make_unique<Handle>(make_scale(file, "frame", 0, L_.n_bays_max() + 1));
  for (std::size_t k = 1; k < ds_.size(); ++k) {
    const std::string what = k < fields.size() ? fields[k].name : "message or session";
    check(H5DSattach_scale(ds_[k].ds.get(), run, 0), "attach /runs/run_index to " + what);
    const Scale s = k < fields.size() ? fields[k].scale : Scale::none;
    if (s != Scale::none)
      check(H5DSattach_scale(ds_[k].ds.get(), s == Scale::bay ? bay.get() : frame->get(), 1),
            "attach a scale to " + what);
  }
}

// The dataset of chunk column k (ChunkColumns order: the fields, then the session) in ds_ (the
// fields, the message, the session).
std::size_t ResultStore::dataset_of(std::size_t k) const { return k < L_.fields().size() ? k : k + 1; }

void ResultStore::extend(std::int64_t n_runs) { n_ = std::max(n_, n_runs); }

// The datasets' rows in the file follow the planned runs lazily: to all of them, once a chunk needs
// rows past the file's (a call per dataset, each a metadata update: once per chunk at most instead
// of once per round of a method with many short rounds). They never shrink: HDF5 rewrites a partial
// chunk through its own filters when a dataset shrinks.
void ResultStore::extend_file_to(std::int64_t rows) {
  if (rows <= file_rows_) return;
  for (const Dataset& d : ds_) {
    const hsize_t dims[2] = {static_cast<hsize_t>(n_), d.width};
    check(H5Dset_extent(d.ds.get(), dims), fmt::format("extend the per-run datasets to {} runs", n_));
  }
  file_rows_ = n_;
}

std::vector<ChunkAddress> ResultStore::place(const ChunkReport& r) {
  const std::int64_t n_chunks = (n_ + chunk_ - 1) / chunk_;
  if (r.index < 0 || r.index >= n_chunks || r.rows != std::min(chunk_, n_ - r.index * chunk_))
    throw std::runtime_error(fmt::format("a report of chunk {} with {} rows, of {} runs in chunks of {}", r.index,
                                         r.rows, n_, chunk_));
  if (r.sizes.size() != cols_.columns.size() || r.masks.size() != r.sizes.size())
    throw std::runtime_error(fmt::format("chunk {}: a report of {} datasets", r.index, r.sizes.size()));
  placed_.resize(static_cast<std::size_t>(n_chunks), 0);
  if (placed_[static_cast<std::size_t>(r.index)])
    throw std::runtime_error(fmt::format("chunk {} placed twice", r.index));
  placed_[static_cast<std::size_t>(r.index)] = 1;
  ++n_placed_;
  extend_file_to(r.index * chunk_ + r.rows);
  std::vector<ChunkAddress> at;
  const hsize_t offset[2] = {static_cast<hsize_t>(r.index * chunk_), 0};
  for (std::size_t k = 0; k < cols_.columns.size(); ++k) {
    Placement p(placement_);
    check(H5Dwrite_chunk(ds_[dataset_of(k)].ds.get(), H5P_DEFAULT, r.masks[k], offset, r.sizes[k], Placement::kBytes),
          fmt::format("place chunk {} of dataset {}", r.index, k));
    at.push_back(p.address());
    if (at.back().size != r.sizes[k])
      throw std::runtime_error(
          fmt::format("chunk {}: HDF5 placed {} bytes of {}", r.index, at.back().size, r.sizes[k]));
  }
  write_messages(r);
  return at;
}

// The chunk's non-empty messages, through HDF5's own filters (variable-length strings live in the
// global heap); a chunk without one is left unwritten, which HDF5 reads as empty strings (NULL in
// C), the variable-length fill value.
void ResultStore::write_messages(const ChunkReport& r) {
  if (r.messages.empty()) return;
  const Dataset& d = ds_[L_.fields().size()];
  std::vector<hsize_t> rows;
  std::vector<const char*> text;
  for (const auto& [row, m] : r.messages) {
    if (row < 0 || row >= r.rows) throw std::runtime_error(fmt::format("chunk {}: a message of row {}", r.index, row));
    rows.push_back(static_cast<hsize_t>(r.index * chunk_ + row));
    text.push_back(m.c_str());
  }
  const std::string what = fmt::format("the messages of chunk {}", r.index);
  Handle fspace(H5Dget_space(d.ds.get()), H5Sclose, "space of " + what);
  check(H5Sselect_elements(fspace.get(), H5S_SELECT_SET, rows.size(), rows.data()), "select " + what);
  const hsize_t count = rows.size();
  Handle mspace(H5Screate_simple(1, &count, nullptr), H5Sclose, "memory space of " + what);
  const Handle type = string_type();
  check(H5Dwrite(d.ds.get(), type.get(), mspace.get(), fspace.get(), H5P_DEFAULT, text.data()), "write " + what);
}

void ResultStore::finish() const {
  const std::int64_t n_chunks = (n_ + chunk_ - 1) / chunk_;
  if (n_placed_ != n_chunks || file_rows_ != n_)
    throw std::runtime_error(fmt::format("internal: {} of {} chunks placed at the end, {} of {} rows in the file",
                                         n_placed_, n_chunks, file_rows_, n_));
}

}  // namespace truss::results
