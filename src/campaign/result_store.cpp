#include "campaign/result_store.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <hdf5_hl.h>

namespace truss::campaign {

using namespace io::h5;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Handle make_group(hid_t loc, const std::string& name) {
  return Handle(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create group " + name);
}

// A chunked, compressed dataset of n rows (x width columns when width > 0), chunks of `chunk`
// whole rows: a chunk of runs goes in with one contiguous copy per dataset. Byte shuffle then deflate: both are
// pure functions of a chunk's values, so the stored values, and each chunk's bytes, do not depend
// on the ranks or the order in which runs finished.
Handle make_chunked(hid_t loc, const std::string& name, hid_t type, const char* units, std::int64_t n,
                    std::int64_t width, std::int64_t chunk, int deflate) {
  const hsize_t dims[2] = {static_cast<hsize_t>(n), static_cast<hsize_t>(width)};
  Handle space(H5Screate_simple(width > 0 ? 2 : 1, dims, nullptr), H5Sclose, "dataspace for " + name);
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, "dataset properties for " + name);
  if (n > 0) {
    const hsize_t cdims[2] = {static_cast<hsize_t>(std::min(chunk, n)), static_cast<hsize_t>(std::max<std::int64_t>(width, 1))};
    check(H5Pset_chunk(dcpl.get(), width > 0 ? 2 : 1, cdims), "chunk " + name);
    if (deflate > 0 && H5Tis_variable_str(type) <= 0) check(H5Pset_shuffle(dcpl.get()), "shuffle " + name);
    if (deflate > 0) check(H5Pset_deflate(dcpl.get(), static_cast<unsigned>(deflate)), "deflate " + name);
  }
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

void attach(hid_t ds, hid_t scale, unsigned dim, const std::string& what) {
  check(H5DSattach_scale(ds, scale, dim), "attach a dimension scale to " + what);
}

// Writes rows [first, first + rows) of `ds` (width columns; 0: a 1-D dataset) from rows x width
// contiguous values in row-major order: whole rows, so HDF5 copies contiguous blocks.
void write_rows(hid_t ds, hid_t mem_type, const void* data, std::int64_t first, std::int64_t rows, std::int64_t width,
                const std::string& what) {
  Handle fspace(H5Dget_space(ds), H5Sclose, "space of " + what);
  const hsize_t fstart[2] = {static_cast<hsize_t>(first), 0};
  const hsize_t fcount[2] = {static_cast<hsize_t>(rows), static_cast<hsize_t>(std::max<std::int64_t>(width, 1))};
  check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, fstart, nullptr, fcount, nullptr), "select " + what);
  Handle mspace(H5Screate_simple(width > 0 ? 2 : 1, fcount, nullptr), H5Sclose, "memory space of " + what);
  check(H5Dwrite(ds, mem_type, mspace.get(), fspace.get(), H5P_DEFAULT, data), "write " + what);
}

}  // namespace

struct ResultStore::Chunk {
  std::int64_t first = 0, rows = 0, filled = 0;
  std::vector<std::uint8_t> have;
  std::vector<std::int8_t> status;
  std::vector<std::string> message;
  std::vector<double> f64;              // [column][row]
  std::vector<std::int64_t> i64;        // [column][row]
  std::vector<double> bays;             // [field][row][bay]: each field's rows contiguous
  std::vector<double> inputs;           // per dispersion k, from rows * offset[k]: [row][its dimensions]
  std::vector<double> wall;
  std::vector<std::int64_t> index, rank, session;
};

struct ResultStore::Datasets {
  std::vector<Handle> keep;  // groups
  Handle status_type = status_enum_type();
  Handle str_type = string_type();
  std::vector<Handle> f64, i64, bays, inputs;
  std::vector<Handle> misc;  // run_index, status, message, run_wall_time_s, rank, session
};

std::string StoreOptions::validate() const {
  if (chunk_runs < 1) return fmt::format("chunk_runs: must be >= 1, got {}", chunk_runs);
  if (deflate_level < 0 || deflate_level > 9) return fmt::format("deflate_level: must be 0 to 9, got {}", deflate_level);
  return {};
}

ResultStore::ResultStore(hid_t file, const CampaignContext& ctx, const StoreOptions& opts)
    : ctx_(ctx), n_(ctx.options.ensemble.n_runs), chunk_(std::max<std::int64_t>(1, opts.chunk_runs)),
      deflate_(opts.deflate_level),
      done_(static_cast<std::size_t>(n_), 0), ds_(std::make_unique<Datasets>()) {
  if (const std::string e = opts.validate(); !e.empty()) throw std::invalid_argument("result store: " + e);
  const OutputColumns& cols = ctx.columns;
  Datasets& d = *ds_;
  const std::int64_t nb = cols.n_bays_max;
  Handle runs = make_group(file, "runs");
  Handle bays = make_group(runs.get(), "bays");
  Handle inputs = make_group(runs.get(), "inputs");
  Handle timing = make_group(file, "timing");
  d.misc.push_back(make_chunked(runs.get(), "run_index", H5T_STD_I64LE, "1", n_, 0, chunk_, deflate_));
  d.misc.push_back(make_chunked(runs.get(), "status", d.status_type.get(), "1", n_, 0, chunk_, deflate_));
  d.misc.push_back(make_chunked(runs.get(), "message", d.str_type.get(), "1", n_, 0, chunk_, deflate_));
  d.misc.push_back(make_chunked(timing.get(), "run_wall_time_s", H5T_IEEE_F64LE, "s", n_, 0, chunk_, deflate_));
  d.misc.push_back(make_chunked(timing.get(), "rank", H5T_STD_I64LE, "1", n_, 0, chunk_, deflate_));
  d.misc.push_back(make_chunked(timing.get(), "session", H5T_STD_I64LE, "1", n_, 0, chunk_, deflate_));
  for (const auto* f : cols.f64) d.f64.push_back(make_chunked(runs.get(), f->name, H5T_IEEE_F64LE, f->units, n_, 0, chunk_, deflate_));
  for (const auto* f : cols.i64) d.i64.push_back(make_chunked(runs.get(), f->name, H5T_STD_I64LE, f->units, n_, 0, chunk_, deflate_));
  for (const auto* f : cols.bay) d.bays.push_back(make_chunked(bays.get(), f->name, H5T_IEEE_F64LE, f->units, n_, nb, chunk_, deflate_));
  const DimensionLayout& L = ctx.sampler.layout();
  for (std::size_t k = 0; k < ctx.options.dispersions.size(); ++k) {
    const DispersionOptions& disp = ctx.options.dispersions[k];
    const std::string units = find_key_units(disp.key);
    d.inputs.push_back(make_chunked(inputs.get(), disp.key, H5T_IEEE_F64LE, units.c_str(), n_,
                                    disp.per == Per::run ? 0 : L.count[k], chunk_, deflate_));
  }
  attach_scales(file, d);
  d.keep.push_back(std::move(runs));
  d.keep.push_back(std::move(bays));
  d.keep.push_back(std::move(inputs));
  d.keep.push_back(std::move(timing));
}

// Dimension scales, so that netCDF-4 readers (xarray) see named dimensions: /runs/run_index
// ("run_index") on the rows of every per-run dataset, /bay (1..n_bays_max) on the columns of the
// per-bay ones, /frame (0..n_bays_max) on those of per-frame inputs.
void ResultStore::attach_scales(hid_t file, Datasets& d) {
  const std::int64_t nb = ctx_.columns.n_bays_max;
  const hid_t run = d.misc[0].get();
  check(H5DSset_scale(run, "run_index"), "make /runs/run_index a dimension scale");
  Handle bay = make_scale(file, "bay", 1, nb);
  const auto& disps = ctx_.options.dispersions;
  bool frames = false;
  for (const auto& disp : disps) frames = frames || disp.per == Per::frame;
  std::unique_ptr<Handle> frame;
  if (frames) frame = std::make_unique<Handle>(make_scale(file, "frame", 0, nb + 1));
  for (std::size_t k = 1; k < d.misc.size(); ++k) attach(d.misc[k].get(), run, 0, "a per-run dataset");
  for (auto* group : {&d.f64, &d.i64}) for (auto& h : *group) attach(h.get(), run, 0, "a /runs column");
  for (auto& h : d.bays) {
    attach(h.get(), run, 0, "a /runs/bays dataset");
    attach(h.get(), bay.get(), 1, "a /runs/bays dataset");
  }
  for (std::size_t k = 0; k < d.inputs.size(); ++k) {
    attach(d.inputs[k].get(), run, 0, disps[k].key);
    if (disps[k].per != Per::run) attach(d.inputs[k].get(), disps[k].per == Per::bay ? bay.get() : frame->get(), 1, disps[k].key);
  }
}

ResultStore::~ResultStore() = default;

ResultStore::Chunk& ResultStore::chunk_for(std::int64_t run) {
  const std::int64_t k = run / chunk_;
  auto it = open_.find(k);
  if (it != open_.end()) return *it->second;
  std::unique_ptr<Chunk> c;
  if (!spare_.empty()) {
    c = std::move(spare_.back());
    spare_.pop_back();
  } else {
    c = std::make_unique<Chunk>();
  }
  const OutputColumns& cols = ctx_.columns;
  c->first = k * chunk_;
  c->rows = std::min(chunk_, n_ - c->first);
  c->filled = 0;
  const auto r = static_cast<std::size_t>(c->rows);
  c->have.assign(r, 0);
  c->status.assign(r, 0);
  c->message.assign(r, {});
  c->f64.resize(cols.f64.size() * r);
  c->i64.resize(cols.i64.size() * r);
  c->bays.resize(cols.bay.size() * r * static_cast<std::size_t>(cols.n_bays_max));
  c->inputs.resize(r * static_cast<std::size_t>(cols.n_inputs));
  c->wall.resize(r);
  c->index.resize(r);
  c->rank.resize(r);
  c->session.resize(r);
  Chunk& ref = *c;
  open_.emplace(k, std::move(c));
  peak_chunks_ = std::max(peak_chunks_, open_.size());
  return ref;
}

void ResultStore::add(const RunRecord& rec, int session) {
  if (rec.run_index < 0 || rec.run_index >= n_) throw std::runtime_error(fmt::format("run index {} out of range", rec.run_index));
  if (done_[static_cast<std::size_t>(rec.run_index)]) throw std::runtime_error(fmt::format("run {} received twice", rec.run_index));
  Chunk& c = chunk_for(rec.run_index);
  const auto i = static_cast<std::size_t>(rec.run_index - c.first);
  const auto r = static_cast<std::size_t>(c.rows);
  const OutputColumns& cols = ctx_.columns;
  const auto nb = static_cast<std::size_t>(cols.n_bays_max);
  done_[static_cast<std::size_t>(rec.run_index)] = 1;
  ++n_done_;
  if (rec.status != sim::RunStatus::ok) ++n_failed_;
  ++status_counts_[static_cast<std::size_t>(rec.status)];
  c.have[i] = 1;
  c.status[i] = static_cast<std::int8_t>(rec.status);
  c.message[i] = rec.message;
  for (std::size_t k = 0; k < cols.f64.size(); ++k) c.f64[k * r + i] = rec.f64[k];
  for (std::size_t k = 0; k < cols.i64.size(); ++k) c.i64[k * r + i] = rec.i64[k];
  for (std::size_t k = 0; k < cols.bay.size(); ++k)
    std::copy_n(rec.bays.begin() + static_cast<std::ptrdiff_t>(k * nb), nb, c.bays.begin() + static_cast<std::ptrdiff_t>((k * r + i) * nb));
  const DimensionLayout& L = ctx_.sampler.layout();
  for (std::size_t k = 0; k < L.count.size(); ++k) {
    const auto off = static_cast<std::size_t>(L.offset[k]), w = static_cast<std::size_t>(L.count[k]);
    std::copy_n(rec.inputs.begin() + static_cast<std::ptrdiff_t>(off), w, c.inputs.begin() + static_cast<std::ptrdiff_t>(r * off + i * w));
  }
  c.wall[i] = rec.wall_time_s;
  c.index[i] = rec.run_index;
  c.rank[i] = rec.rank;
  c.session[i] = session;
  if (++c.filled < c.rows) return;
  write_chunk(c);
  auto it = open_.find(c.first / chunk_);
  spare_.push_back(std::move(it->second));
  open_.erase(it);
  if (spare_.size() > 2) spare_.resize(2);
}

void ResultStore::write_chunk(const Chunk& c) {
  const OutputColumns& cols = ctx_.columns;
  Datasets& d = *ds_;
  const std::int64_t r = c.rows, nb = cols.n_bays_max;
  const auto ur = static_cast<std::size_t>(r);
  const std::string at = fmt::format(" (runs {} to {})", c.first, c.first + r - 1);
  write_rows(d.misc[0].get(), H5T_NATIVE_INT64, c.index.data(), c.first, r, 0, "/runs/run_index" + at);
  write_rows(d.misc[1].get(), d.status_type.get(), c.status.data(), c.first, r, 0, "/runs/status" + at);
  std::vector<const char*> msg(ur);
  for (std::size_t i = 0; i < ur; ++i) msg[i] = c.message[i].c_str();
  write_rows(d.misc[2].get(), d.str_type.get(), msg.data(), c.first, r, 0, "/runs/message" + at);
  write_rows(d.misc[3].get(), H5T_NATIVE_DOUBLE, c.wall.data(), c.first, r, 0, "/timing/run_wall_time_s" + at);
  write_rows(d.misc[4].get(), H5T_NATIVE_INT64, c.rank.data(), c.first, r, 0, "/timing/rank" + at);
  write_rows(d.misc[5].get(), H5T_NATIVE_INT64, c.session.data(), c.first, r, 0, "/timing/session" + at);
  for (std::size_t k = 0; k < d.f64.size(); ++k)
    write_rows(d.f64[k].get(), H5T_NATIVE_DOUBLE, c.f64.data() + k * ur, c.first, r, 0, cols.f64[k]->name + at);
  for (std::size_t k = 0; k < d.i64.size(); ++k)
    write_rows(d.i64[k].get(), H5T_NATIVE_INT64, c.i64.data() + k * ur, c.first, r, 0, cols.i64[k]->name + at);
  for (std::size_t k = 0; k < d.bays.size(); ++k)
    write_rows(d.bays[k].get(), H5T_NATIVE_DOUBLE, c.bays.data() + k * ur * static_cast<std::size_t>(nb), c.first, r, nb,
               cols.bay[k]->name + at);
  const DimensionLayout& L = ctx_.sampler.layout();
  for (std::size_t k = 0; k < d.inputs.size(); ++k)
    write_rows(d.inputs[k].get(), H5T_NATIVE_DOUBLE, c.inputs.data() + ur * static_cast<std::size_t>(L.offset[k]), c.first, r,
               ctx_.options.dispersions[k].per == Per::run ? 0 : L.count[k], ctx_.options.dispersions[k].key + at);
}

void ResultStore::check_complete() const {
  if (n_done_ != n_ || !open_.empty())
    throw std::runtime_error(fmt::format("internal: {} of {} runs stored, {} chunks unwritten", n_done_, n_, open_.size()));
}

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

}  // namespace truss::campaign
