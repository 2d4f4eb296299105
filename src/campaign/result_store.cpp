#include "campaign/result_store.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <hdf5_hl.h>

#include "campaign/chunk_codec.hpp"
#include "campaign/column_stats.hpp"
#include "campaign/result_store_parts.hpp"
#include "campaign/store_jobs.hpp"

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
  auto add = [&](hid_t loc, const std::string& name, hid_t type, const char* units, std::int64_t width, std::size_t elem) {
    d.direct.push_back({make_chunked(loc, name, type, units, n_, width, chunk_, deflate_), elem,
                        static_cast<std::size_t>(std::max<std::int64_t>(width, 1)), width > 0 ? 2 : 1});
  };
  add(runs.get(), "run_index", H5T_STD_I64LE, "1", 0, 8);
  add(runs.get(), "status", d.status_type.get(), "1", 0, 1);
  d.message = std::make_unique<Handle>(make_chunked(runs.get(), "message", d.str_type.get(), "1", n_, 0, chunk_, deflate_));
  add(timing.get(), "run_wall_time_s", H5T_IEEE_F64LE, "s", 0, 8);
  add(timing.get(), "rank", H5T_STD_I64LE, "1", 0, 8);
  add(timing.get(), "session", H5T_STD_I64LE, "1", 0, 8);
  d.f64_0 = d.direct.size();
  for (const auto* f : cols.f64) add(runs.get(), f->name, H5T_IEEE_F64LE, f->units, 0, 8);
  d.i64_0 = d.direct.size();
  for (const auto* f : cols.i64) add(runs.get(), f->name, H5T_STD_I64LE, f->units, 0, 8);
  d.bays_0 = d.direct.size();
  for (const auto* f : cols.bay) add(bays.get(), f->name, H5T_IEEE_F64LE, f->units, nb, 8);
  d.inputs_0 = d.direct.size();
  const DimensionLayout& L = ctx.sampler.layout();
  for (std::size_t k = 0; k < ctx.options.dispersions.size(); ++k) {
    const DispersionOptions& disp = ctx.options.dispersions[k];
    const std::string units = find_key_units(disp.key);
    add(inputs.get(), disp.key, H5T_IEEE_F64LE, units.c_str(), disp.per == Per::run ? 0 : L.count[k], 8);
  }
  attach_scales(file, d);
  d.keep.push_back(std::move(runs));
  d.keep.push_back(std::move(bays));
  d.keep.push_back(std::move(inputs));
  d.keep.push_back(std::move(timing));
  std::size_t chunk_bytes = 0;
  for (const auto& x : d.direct) chunk_bytes += static_cast<std::size_t>(std::min(chunk_, n_)) * x.width * x.elem;
  max_jobs_bytes_ = opts.offload_encoding ? 2 * chunk_bytes : 0;
  pool_.set_limit(2 * chunk_bytes);
  headroom_ = opts.job_headroom_bytes;
  track_ = std::make_unique<Tracking>();
  track_->first.assign(d.direct.size(), -1);
  std::int64_t k = 0;
  for (std::size_t j = d.f64_0; j < d.i64_0; ++j) track_->first[j] = k++;
  for (std::size_t j = d.bays_0; j < d.inputs_0; ++j, k += nb) track_->first[j] = k;
  track_->col.assign(static_cast<std::size_t>(k), ColumnStats((n_ + chunk_ - 1) / chunk_));
  hbool_t threadsafe = 0;
  if (opts.write_thread && H5is_library_threadsafe(&threadsafe) >= 0 && threadsafe) {
    writes_ = std::make_unique<TaskThread>(2 * chunk_bytes);  // the messages held: encoded chunks and the records around them
    // A thread-safe HDF5 keeps the error-stack settings per thread: errors come back as exceptions here too.
    writes_->post([] { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }, 0);
  }
}

// Dimension scales, so that netCDF-4 readers (xarray) see named dimensions: /runs/run_index
// ("run_index") on the rows of every per-run dataset, /bay (1..n_bays_max) on the columns of the
// per-bay ones, /frame (0..n_bays_max) on those of per-frame inputs.
void ResultStore::attach_scales(hid_t file, Datasets& d) {
  const std::int64_t nb = ctx_.columns.n_bays_max;
  const hid_t run = d.direct[0].ds.get();
  check(H5DSset_scale(run, "run_index"), "make /runs/run_index a dimension scale");
  Handle bay = make_scale(file, "bay", 1, nb);
  const auto& disps = ctx_.options.dispersions;
  bool frames = false;
  for (const auto& disp : disps) frames = frames || disp.per == Per::frame;
  std::unique_ptr<Handle> frame;
  if (frames) frame = std::make_unique<Handle>(make_scale(file, "frame", 0, nb + 1));
  attach(d.direct[1].ds.get(), run, 0, "/runs/status");  // the order of the older files' REFERENCE_LIST
  attach(d.message->get(), run, 0, "/runs/message");
  for (std::size_t k = 2; k < d.inputs_0; ++k) attach(d.direct[k].ds.get(), run, 0, "a per-run dataset");
  for (std::size_t k = d.bays_0; k < d.inputs_0; ++k) attach(d.direct[k].ds.get(), bay.get(), 1, "a /runs/bays dataset");
  for (std::size_t k = 0; k < disps.size(); ++k) {
    const hid_t ds = d.direct[d.inputs_0 + k].ds.get();
    attach(ds, run, 0, disps[k].key);
    if (disps[k].per != Per::run) attach(ds, disps[k].per == Per::bay ? bay.get() : frame->get(), 1, disps[k].key);
  }
}

ResultStore::~ResultStore() { writes_.reset(); }  // before the datasets close


// A complete chunk: the messages through H5Dwrite, every other dataset's chunk written raw
// (level 0) or queued as an encoding job; a backlog past two chunks is encoded here.
void ResultStore::complete_chunk(Chunk& c) {
  Datasets& d = *ds_;
  const auto r = static_cast<std::size_t>(c.rows);
  std::vector<std::uint8_t> use(r);  // ok runs (status 0) feed the statistics
  for (std::size_t i = 0; i < r; ++i) use[i] = c.buf[1][kJobHeader + i] == 0;
  std::vector<const char*> msg(r);
  for (std::size_t i = 0; i < r; ++i) msg[i] = c.message[i].c_str();
  write_rows(d.message->get(), d.str_type.get(), msg.data(), c.first, c.rows, 0,
             fmt::format("/runs/message (runs {} to {})", c.first, c.first + c.rows - 1));
  auto take_small = [&] {
    std::lock_guard<std::mutex> lock(jobs_m_);
    std::string b = pool_.take(kJobBytes + kJobBytes / 4 + headroom_);
    b.clear();
    return b;
  };
  std::vector<std::string> made;  // queued together, once the chunk is done
  std::string small = take_small();  // small chunks grouped into one job
  for (std::size_t j = 0; j < d.direct.size(); ++j) {
    std::string& b = c.buf[j];
    JobHeader h{static_cast<std::uint32_t>(j), static_cast<std::uint32_t>(d.direct[j].elem), c.first / chunk_, deflate_, 0,
                b.size() - kJobHeader, 0};
    const bool stats = track_->first[j] >= 0;
    if (deflate_ == 0) {  // the stored bytes are the raw bytes: written now; a job only for the statistics
      std::memcpy(b.data(), &h, kJobHeader);
      write_encoded(b);
      if (!stats) continue;
      h.level = kStatsOnly;
    }
    if (stats) h.stats_bytes = append_request(b, j, use);
    std::memcpy(b.data(), &h, kJobHeader);
    if (b.size() < kJobBytes / 4) {  // copied into the group: the chunk keeps its buffer
      small += b;
      if (small.size() < kJobBytes && j + 1 < d.direct.size()) continue;
      made.push_back(std::move(small));
      small = take_small();
      continue;
    }
    made.push_back(std::move(b));
  }
  const bool spare_small = small.empty();
  if (!spare_small) made.push_back(std::move(small));
  {
    std::lock_guard<std::mutex> lock(jobs_m_);
    if (spare_small) pool_.give(std::move(small));
    for (std::string& job : made) {
      jobs_bytes_ += job.size();
      jobs_.push_back(std::move(job));
    }
  }
  while (over_backlog() && drain_one()) {
  }
}

bool ResultStore::over_backlog() {
  std::lock_guard<std::mutex> lock(jobs_m_);
  return jobs_bytes_ > max_jobs_bytes_;
}

void ResultStore::recycle(std::string&& buffer) {
  std::lock_guard<std::mutex> lock(jobs_m_);
  pool_.give(std::move(buffer));
}

bool ResultStore::pop_job(std::string& job) {
  std::lock_guard<std::mutex> lock(jobs_m_);
  if (jobs_.empty()) return false;
  job = std::move(jobs_.front());
  jobs_.pop_front();
  jobs_bytes_ -= job.size();
  return true;
}

bool ResultStore::take_job(std::string& job) {
  if (!pop_job(job)) return false;
  ++jobs_out_;
  return true;
}

void ResultStore::job_done(std::string_view output) {
  write_encoded(output);
  --jobs_out_;
  ++jobs_returned_;
}

void ResultStore::job_done(std::shared_ptr<const char[]> owner, std::size_t owner_bytes, std::string_view output) {
  if (!writes_) {
    job_done(output);
    return;
  }
  writes_->post([this, owner = std::move(owner), output] { write_encoded(output); }, std::max(owner_bytes, output.size()));
  --jobs_out_;
  ++jobs_returned_;
}

void ResultStore::finish_writes() {
  if (!writes_) return;
  post_staged();
  writes_->drain();
}

double ResultStore::calc_write_thread_cpu_s() const { return writes_ ? writes_->calc_cpu_s() : 0.0; }

void ResultStore::drain_jobs() {
  finish_writes();  // the last chunks may still be completing on the write thread
  while (drain_one()) {
  }
}

bool ResultStore::drain_one() {
  std::string job;
  if (!pop_job(job)) return false;
  std::string out;
  encode_job_output(job, out);
  {
    std::lock_guard<std::mutex> lock(jobs_m_);
    pool_.give(std::move(job));
  }
  write_encoded(out);
  ++jobs_local_;
  return true;
}

// Appends the statistics request of dataset j's chunk to its job part: the rows, the ok runs and
// each column's windows (first seeded from this chunk if it is the first to complete). Returns its size.
std::uint64_t ResultStore::append_request(std::string& part, std::size_t j, const std::vector<std::uint8_t>& use) {
  const std::size_t width = ds_->direct[j].width, rows = use.size(), before = part.size();
  std::lock_guard<std::mutex> lock(stats_m_);  // the write thread may be merging into these columns
  auto* first = &track_->col[static_cast<std::size_t>(track_->first[j])];
  if (!first->seeded())
    for (std::size_t b = 0; b < width; ++b) first[b].seed(part.data() + kJobHeader + 8 * b, rows, width, use.data());
  const std::uint32_t rw[2] = {static_cast<std::uint32_t>(rows), static_cast<std::uint32_t>(width)};
  part.append(reinterpret_cast<const char*>(rw), sizeof rw);
  part.append(reinterpret_cast<const char*>(use.data()), rows);
  for (std::size_t b = 0; b < width; ++b) append_windows(part, first[b].windows());
  return part.size() - before;
}

void ResultStore::write_encoded(std::string_view output) {
  const Datasets& d = *ds_;
  for_each_part(output, "an encoded chunk", [&](const JobHeader& h, std::string_view bytes, std::string_view stats) {
    if (h.dataset >= d.direct.size() || h.chunk < 0 || h.chunk * chunk_ >= n_)
      throw std::runtime_error(fmt::format("an encoded chunk for dataset {} chunk {}: no such chunk", h.dataset, h.chunk));
    const hsize_t offset[2] = {static_cast<hsize_t>(h.chunk * chunk_), 0};
    if (h.level != kStatsOnly)
      check(H5Dwrite_chunk(d.direct[h.dataset].ds.get(), H5P_DEFAULT, h.mask, offset, bytes.size(), bytes.data()),
            fmt::format("write chunk {} of dataset {}", h.chunk, h.dataset));
    const std::int64_t first = track_->first[h.dataset];
    if (first < 0 || h.stats_bytes == 0) return;  // no statistics, or a raw chunk whose summaries come with its statistics-only job
    std::lock_guard<std::mutex> lock(stats_m_);  // HDF5 (thread-safe build) serialises itself; the statistics are ours
    for (std::size_t b = 0; b < d.direct[h.dataset].width; ++b)
      track_->col[static_cast<std::size_t>(first) + b].add(h.chunk, read_summary(stats));
    if (!stats.empty()) throw std::runtime_error(fmt::format("{} bytes past the summaries of dataset {}", stats.size(), h.dataset));
  });
}

StreamedStats ResultStore::calc_stats() {
  finish_writes();
  const Datasets& d = *ds_;
  StreamedStats s;
  auto one = [&](std::size_t k, std::vector<std::uint8_t>& resolved) {
    if (!track_->col[k].complete()) throw std::runtime_error(fmt::format("internal: statistics of column {} miss a chunk", k));
    bool ok = true;
    const Stats st = track_->col[k].calc_stats(ok);
    resolved.push_back(ok);
    return st;
  };
  for (std::size_t j = d.f64_0; j < d.i64_0; ++j) s.f64.push_back(one(static_cast<std::size_t>(track_->first[j]), s.f64_resolved));
  for (std::size_t j = d.bays_0; j < d.inputs_0; ++j) {
    auto& st = s.bays.emplace_back();
    auto& ok = s.bays_resolved.emplace_back();
    for (std::size_t b = 0; b < d.direct[j].width; ++b) st.push_back(one(static_cast<std::size_t>(track_->first[j]) + b, ok));
  }
  for (const auto& c : track_->col) s.kept_values += c.kept_values();
  return s;
}

void ResultStore::check_complete() {
  finish_writes();
  if (n_done_ != n_ || !open_.empty() || !jobs_.empty() || jobs_out_ != 0)
    throw std::runtime_error(fmt::format("internal: {} of {} runs stored, {} chunks unwritten, {} encoding jobs waiting, {} out",
                                         n_done_, n_, open_.size(), jobs_.size(), jobs_out_));
}

}  // namespace truss::campaign
