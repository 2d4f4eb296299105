#include "results/result_store.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>
#include <hdf5_hl.h>

#include "util/bytes.hpp"

namespace truss::results {

using namespace io::h5;
using campaign::Field;
using campaign::RecordLayout;
using campaign::Scale;
using campaign::ValueType;

// A chunk of runs in memory, until every row has arrived and the chunk is written: each record's
// fields scattered on arrival into the chunk's column blocks, one per field (field f's block at
// chunk_runs x f.offset, its row i at i x f.bytes()), so that a dataset chunk is one contiguous
// block when it is written (gathering a field from whole records at write time would read one cache
// line of a record per value).
struct ResultStore::Chunk {
  std::int64_t index = 0, filled = 0;
  std::unique_ptr<char[]> cols;  // chunk_runs x fixed_bytes, by field
  std::vector<std::string> message;
  std::vector<std::int64_t> session;
  std::vector<std::uint8_t> use;  // ok runs (status 0): they feed the statistics
};

// One per-run dataset: a record field (`field` >= 0), /runs/message (kMessage) or /timing/session
// (kSession). `stats`: the first of its output columns' statistics in col_, or -1.
struct ResultStore::Dataset {
  static constexpr int kMessage = -1, kSession = -2;
  Handle ds;
  int field = kMessage;
  std::size_t elem = 8, width = 1;
  int stats = -1;
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

std::string StoreOptions::validate() const {
  if (chunk_runs < 1) return fmt::format("chunk_runs: must be >= 1, got {}", chunk_runs);
  if (deflate_level < 0 || deflate_level > 9)
    return fmt::format("deflate_level: must be 0 to 9, got {}", deflate_level);
  return {};
}

ResultStore::ResultStore(hid_t file, const campaign::RecordLayout& layout, const StoreOptions& opts)
    : L_(layout), chunk_(opts.chunk_runs), deflate_(opts.deflate_level) {
  if (const std::string e = opts.validate(); !e.empty()) throw std::invalid_argument("result store: " + e);
  create_datasets(file);
}

ResultStore::~ResultStore() = default;

// Every field's dataset in its group, then the message and the session; dimension scales, so that
// netCDF-4 readers (xarray) see named dimensions: /runs/run_index on the rows of every per-run
// dataset, /bay (1..n_bays_max) and /frame (0..n_bays_max) on the columns of the per-bay and
// per-frame ones. Statistics: one ColumnStats per output column (per bay for per-bay outputs).
void ResultStore::create_datasets(hid_t file) {
  for (const char* g : {"runs", "runs/bays", "runs/inputs", "timing"}) groups_.push_back(create_group(file, g));
  const Handle status_type = status_enum_type(), str_type = string_type();
  const auto& fields = L_.fields();
  for (std::size_t f = 0; f < fields.size(); ++f) {
    const Field& fd = fields[f];
    const hid_t type = fd.type == ValueType::status ? status_type.get()
                       : fd.type == ValueType::i64  ? H5T_STD_I64LE
                                                    : H5T_IEEE_F64LE;
    Dataset d{make_dataset(groups_[static_cast<std::size_t>(fd.group)].get(), fd.name, type, fd.units,
                           fd.scale != Scale::none, fd.width, chunk_, deflate_),
              static_cast<int>(f), campaign::value_bytes(fd.type), static_cast<std::size_t>(fd.width)};
    if (fd.statistics) {
      d.stats = static_cast<int>(col_.size());
      col_.resize(col_.size() + d.width);
    }
    ds_.push_back(std::move(d));
  }
  ds_.push_back({make_dataset(groups_[0].get(), "message", str_type.get(), "1", false, 1, chunk_, deflate_),
                 Dataset::kMessage});
  ds_.push_back({make_dataset(groups_[3].get(), "session", H5T_STD_I64LE, "1", false, 1, chunk_, deflate_),
                 Dataset::kSession});
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

void ResultStore::extend(std::int64_t n_runs) {
  if (n_runs <= n_) return;
  for (const Dataset& d : ds_) {
    const hsize_t dims[2] = {static_cast<hsize_t>(n_runs), d.width};
    check(H5Dset_extent(d.ds.get(), dims), fmt::format("extend the per-run datasets to {} runs", n_runs));
  }
  n_ = n_runs;
  done_.resize(static_cast<std::size_t>(n_), 0);
}

ResultStore::Chunk& ResultStore::chunk_for(std::int64_t run) {
  const std::int64_t k = run / chunk_;
  if (const auto it = open_.find(k); it != open_.end()) return *it->second;
  auto c = std::make_unique<Chunk>();
  c->index = k;
  c->cols = std::make_unique_for_overwrite<char[]>(static_cast<std::size_t>(chunk_) * L_.fixed_bytes());
  c->message.resize(static_cast<std::size_t>(chunk_));
  c->session.resize(static_cast<std::size_t>(chunk_));
  c->use.resize(static_cast<std::size_t>(chunk_));
  Chunk& ref = *c;
  open_.emplace(k, std::move(c));
  peak_chunks_ = std::max(peak_chunks_, open_.size());
  return ref;
}

void ResultStore::add(const campaign::RecordView& rec, std::int64_t session) {
  const std::int64_t run = rec.run();
  if (run < 0 || run >= n_) throw std::runtime_error(fmt::format("run index {} out of range", run));
  if (done_[static_cast<std::size_t>(run)]) throw std::runtime_error(fmt::format("run {} received twice", run));
  done_[static_cast<std::size_t>(run)] = 1;
  ++n_done_;
  ++status_counts_[static_cast<std::size_t>(rec.status())];
  Chunk& c = chunk_for(run);
  const auto i = static_cast<std::size_t>(run - c.index * chunk_);
  const char* src = rec.bytes().data();
  char* cols = c.cols.get();
  const auto rows = static_cast<std::size_t>(chunk_);
  for (const campaign::Field& f : L_.fields()) {
    const std::size_t bytes = f.bytes();
    char* dst = cols + rows * f.offset + i * bytes;
    std::memcpy(dst, src + f.offset, bytes);
  }
  c.message[i].assign(rec.message());
  c.session[i] = session;
  c.use[i] = rec.bytes()[L_.fields()[RecordLayout::kStatus].offset] == 0;
  if (++c.filled == chunk_) complete_.push_back(c.index);
}

void ResultStore::write_next() {
  const auto it = open_.find(complete_.front());
  write_dataset(*it->second, ds_[next_dataset_], chunk_);
  if (++next_dataset_ < ds_.size()) return;
  next_dataset_ = 0;
  complete_.pop_front();
  open_.erase(it);
}

void ResultStore::finish() {
  while (write_pending()) write_next();
  if (n_done_ != n_)
    throw std::runtime_error(fmt::format("internal: {} of {} runs stored at the end", n_done_, n_));
  for (const auto& [k, c] : open_)  // the last chunk, partial
    for (const Dataset& d : ds_) write_dataset(*c, d, n_ - k * chunk_);
  open_.clear();
}

// Rows [0, rows) of chunk c's dataset d (the rest of the chunk, past the last run, is zeroed):
// its column block filtered and written as one HDF5 chunk; the statistics of its output columns
// merged.
void ResultStore::write_dataset(Chunk& c, const Dataset& d, std::int64_t rows) {
  const auto r = static_cast<std::size_t>(rows);
  const std::string what = fmt::format("chunk {} of {}", c.index,
                                       d.field >= 0 ? L_.fields()[static_cast<std::size_t>(d.field)].name
                                                    : d.field == Dataset::kMessage ? "message" : "session");
  if (d.field == Dataset::kMessage) {  // variable-length strings: through HDF5's own filters
    // A chunk with no message (every run ok, as most are) is left unwritten: HDF5 reads it as empty
    // strings (NULL in C), the vlen fill value.
    if (std::all_of(c.message.begin(), c.message.begin() + static_cast<std::ptrdiff_t>(r),
                    [](const std::string& m) { return m.empty(); }))
      return;
    std::vector<const char*> msg(r);
    for (std::size_t i = 0; i < r; ++i) msg[i] = c.message[i].c_str();
    Handle fspace(H5Dget_space(d.ds.get()), H5Sclose, "space of " + what);
    const hsize_t start = static_cast<hsize_t>(c.index * chunk_), count = r;
    check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, &start, nullptr, &count, nullptr), "select " + what);
    Handle mspace(H5Screate_simple(1, &count, nullptr), H5Sclose, "memory space of " + what);
    const Handle type = string_type();
    check(H5Dwrite(d.ds.get(), type.get(), mspace.get(), fspace.get(), H5P_DEFAULT, msg.data()), "write " + what);
    return;
  }
  const std::size_t bytes = d.width * d.elem, n = static_cast<std::size_t>(chunk_);
  char* block = d.field == Dataset::kSession
                    ? reinterpret_cast<char*>(c.session.data())
                    : c.cols.get() + n * L_.fields()[static_cast<std::size_t>(d.field)].offset;
  std::memset(block + r * bytes, 0, (n - r) * bytes);  // the rows past the last run of a partial chunk
  const std::uint32_t mask = codec_.encode({block, n * bytes}, d.elem, deflate_, encoded_);
  const hsize_t offset[2] = {static_cast<hsize_t>(c.index * chunk_), 0};
  check(H5Dwrite_chunk(d.ds.get(), H5P_DEFAULT, mask, offset, encoded_.size(), encoded_.data()), "write " + what);
  if (d.stats >= 0) merge_stats(d, block, c.index, c.use, rows);
}

void ResultStore::merge_stats(const Dataset& d, const char* block, std::int64_t chunk,
                              const std::vector<std::uint8_t>& use, std::int64_t rows) {
  const auto r = static_cast<std::size_t>(rows);
  for (std::size_t b = 0; b < d.width; ++b) {
    statistics::ColumnStats& col = col_[static_cast<std::size_t>(d.stats) + b];
    const char* values = block + 8 * b;
    if (!col.seeded()) col.seed(values, r, d.width, use.data());
    statistics::calc_chunk_summary(values, r, d.width, use.data(), col.windows(), summary_);
    col.add(chunk, summary_);
  }
}

StreamedStats ResultStore::calc_stats() const {
  const std::int64_t n_chunks = (n_ + chunk_ - 1) / chunk_;
  StreamedStats s;
  auto one = [&](std::size_t k, std::vector<std::uint8_t>& resolved) {
    if (!col_[k].complete(n_chunks))
      throw std::runtime_error(fmt::format("internal: the statistics of column {} miss a chunk", k));
    bool ok = true;
    const statistics::Stats st = col_[k].calc_stats(ok);
    resolved.push_back(ok);
    return st;
  };
  for (const Dataset& d : ds_) {
    if (d.stats < 0) continue;
    const auto k = static_cast<std::size_t>(d.stats);
    if (L_.fields()[static_cast<std::size_t>(d.field)].scale == Scale::none) {
      s.f64.push_back(one(k, s.f64_resolved));
      continue;
    }
    auto& st = s.bays.emplace_back();
    auto& ok = s.bays_resolved.emplace_back();
    for (std::size_t b = 0; b < d.width; ++b) st.push_back(one(k + b, ok));
  }
  for (const auto& c : col_) s.kept_values += c.kept_values();
  return s;
}

}  // namespace truss::results
