// The results file's chunks encoded outside HDF5 (campaign/chunk_codec) against HDF5's own filter
// pipeline, and the result store's encoding jobs (run elsewhere, routed back) against the records'
// values.
#include <catch2/catch.hpp>

#include <hdf5.h>

#include <cmath>
#include <cstring>
#include <deque>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "campaign/campaign.hpp"
#include "campaign/campaign_h5.hpp"
#include "campaign/chunk_codec.hpp"
#include "campaign/result_store.hpp"
#include "campaign/run_record.hpp"
#include "campaign_fixtures.hpp"

using namespace truss::campaign;
namespace fs = std::filesystem;

namespace {

// A file holding a 1-D dataset "x" of n elements of `type` in one chunk, shuffled and deflated at
// `level`; f(dataset) runs on it, then everything is closed and the file removed.
template <class F>
void with_one_chunk_dataset(hid_t type, hsize_t n, int level, F&& f) {
  const std::string path = (fs::temp_directory_path() / "truss_test_chunk_codec.h5").string();
  const hid_t file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hid_t space = H5Screate_simple(1, &n, nullptr);
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dcpl, 1, &n);
  H5Pset_shuffle(dcpl);
  H5Pset_deflate(dcpl, static_cast<unsigned>(level));
  const hid_t ds = H5Dcreate2(file, "x", type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  f(file, ds);
  H5Dclose(ds);
  H5Pclose(dcpl);
  H5Sclose(space);
  H5Fclose(file);
  fs::remove(path);
}

// The chunk HDF5 stores for `raw` (n elements of `type`) when H5Dwrite filters it: read back raw
// with H5Dread_chunk.
std::string hdf5_filtered_chunk(const std::string& raw, hid_t type, std::size_t es, int level, std::uint32_t& mask) {
  std::string stored;
  with_one_chunk_dataset(type, raw.size() / es, level, [&](hid_t file, hid_t ds) {
    REQUIRE(H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw.data()) >= 0);
    H5Fflush(file, H5F_SCOPE_GLOBAL);
    const hsize_t offset = 0;
    hsize_t size = 0;
    REQUIRE(H5Dget_chunk_storage_size(ds, &offset, &size) >= 0);
    stored.assign(size, '\0');
    REQUIRE(H5Dread_chunk(ds, H5P_DEFAULT, &offset, &mask, stored.data()) >= 0);
  });
  return stored;
}

// HDF5 reading `stored` (mask) back through its own filter pipeline (H5Dwrite_chunk, then
// H5Dread): the values a reader of the file sees.
std::string hdf5_read_back(const std::string& stored, std::uint32_t mask, hid_t type, std::size_t es, std::size_t raw_bytes,
                           int level) {
  std::string back(raw_bytes, '\0');
  with_one_chunk_dataset(type, raw_bytes / es, level, [&](hid_t, hid_t ds) {
    const hsize_t offset = 0;
    REQUIRE(H5Dwrite_chunk(ds, H5P_DEFAULT, mask, &offset, stored.size(), stored.data()) >= 0);
    REQUIRE(H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, back.data()) >= 0);
  });
  return back;
}

std::string random_doubles(std::size_t n, bool smooth, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(1.25, smooth ? 1e-3 : 1e3);
  std::vector<double> v(n);
  for (auto& x : v) x = g(rng);
  return std::string(reinterpret_cast<const char*>(v.data()), n * 8);
}

}  // namespace

TEST_CASE("chunk codec: chunks HDF5's shuffle + deflate filters read back, as small as HDF5's own", "[campaign][codec]") {
  struct Case {
    std::string raw;
    hid_t type;
    std::size_t es;
  };
  std::string status(4096, '\0');
  for (std::size_t i = 0; i < status.size(); ++i) status[i] = static_cast<char>(i % 97 == 0 ? 3 : 0);
  const Case cases[] = {{random_doubles(4096, true, 1), H5T_NATIVE_DOUBLE, 8},    // a load column: narrow spread
                        {random_doubles(4096, false, 2), H5T_NATIVE_DOUBLE, 8},   // wide spread, mostly incompressible
                        {random_doubles(4096 * 30, true, 3), H5T_NATIVE_DOUBLE, 8},  // a per-bay chunk (983 kB)
                        {status, H5T_NATIVE_INT8, 1}};                            // statuses: shuffle is a no-op
  for (int level : {1, 6}) {
    for (const Case& c : cases) {
      std::uint32_t hdf5_mask = 99;
      const std::string hdf5 = hdf5_filtered_chunk(c.raw, c.type, c.es, level, hdf5_mask);
      std::string mine;
      const std::uint32_t mask = encode_chunk(c.raw, c.es, level, mine);
      // The deflate stream is libdeflate's, not zlib's: not the same bytes, but HDF5 inflates it to
      // the same values and the same filters are skipped (HDF5's buffer rule). Size: both are
      // DEFLATE at the same level with different match finders; chunk by chunk within 3 % of zlib's
      // (+64 bytes of framing for tiny outputs) -- measured 0.78 to 1.24 of zlib's only on the
      // 4 kB status chunk (tens of bytes), and 0.3 % smaller overall on real Table-1 chunks.
      CHECK(mask == hdf5_mask);
      CHECK(hdf5_read_back(mine, mask, c.type, c.es, c.raw.size(), level) == c.raw);
      INFO("level " << level << ": " << mine.size() << " bytes against zlib's " << hdf5.size());
      CHECK(mine.size() <= hdf5.size() + 3 * hdf5.size() / 100 + 64);
      std::string back;
      decode_chunk(mine, mask, c.es, level, c.raw.size(), back);
      CHECK(back == c.raw);
    }
  }
  std::string plain;
  CHECK(encode_chunk(cases[0].raw, 8, 0, plain) == 0);
  CHECK(plain == cases[0].raw);  // level 0: no filter, the raw bytes
  std::string back;
  CHECK_THROWS(decode_chunk(std::string(100, 'x'), 0, 8, 1, 4096 * 8, back));
}

// The records of `runs` as a worker's message: each behind an 8-byte frame head (as the journal's
// frames are), handed to the store with the message as their owner.
namespace {
void add_message(ResultStore& store, const OutputColumns& cols, const std::vector<std::int64_t>& runs, int session) {
  std::string bytes;
  std::vector<std::size_t> at;
  for (std::int64_t run : runs) {
    at.push_back(bytes.size());
    bytes.append(8, 'F');
    test::distinct_record(cols, run).append_bytes(bytes);
  }
  at.push_back(bytes.size());
  std::shared_ptr<char[]> owner(new char[bytes.size()]);
  std::memcpy(owner.get(), bytes.data(), bytes.size());
  std::vector<std::string_view> views;
  for (std::size_t k = 0; k + 1 < at.size(); ++k) views.emplace_back(owner.get() + at[k], at[k + 1] - at[k]);
  store.add_records(std::move(owner), views, 8, session);
}
}  // namespace

TEST_CASE("result store: encoding jobs run elsewhere land in the right dataset and rows", "[campaign][codec]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 150));
  const OutputColumns& cols = ctx.columns;
  auto record = [&](std::int64_t run) { return test::distinct_record(cols, run); };
  const std::string path = (fs::temp_directory_path() / "truss_test_store_jobs.h5").string();
  std::vector<StreamedStats> stats;
  // Returned outputs written where they arrive, then on the store's write thread (rank 0's, with
  // a thread-safe HDF5): the same rows and the same statistics.
  for (const bool threaded : {false, true}) {
    INFO((threaded ? "on the write thread" : "where they arrive"));
    fs::remove(path);
    const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    {
      // Chunks of 16 runs, offloaded: every job goes out and comes back in reverse order.
      ResultStore store(f, ctx, StoreOptions{16, 1, true, 1024, threaded});
      hbool_t threadsafe = 0;
      H5is_library_threadsafe(&threadsafe);
      CHECK(store.has_write_thread() == (threaded && threadsafe));
      std::vector<std::string> outputs;
      std::string job, out;
      auto take_jobs = [&] {
        if (threaded) store.finish_writes();  // the chunks complete on the write thread
        while (store.take_job(job)) {
          encode_job_output(job, out);
          outputs.push_back(out);
        }
      };
      // Any order of arrival; every third run added alone (rank 0's own, staged for the thread),
      // the others in messages of up to four records behind an 8-byte frame head each (a worker's).
      std::vector<std::int64_t> message_runs;
      for (std::int64_t run = 149; run >= 0; --run) {
        if (run % 3 == 0) {
          store.add(record(run), 2);
        } else {
          message_runs.push_back(run);
          if (message_runs.size() == 4 || run < 3) {
            add_message(store, cols, message_runs, 2);
            message_runs.clear();
          }
        }
        take_jobs();
      }
      CHECK(store.n_done() == 150);
      CHECK_FALSE(store.jobs_pending());
      for (auto it = outputs.rbegin(); it != outputs.rend(); ++it) {
        if (!threaded) {
          store.job_done(*it);
          continue;
        }
        std::shared_ptr<char[]> owner(new char[it->size() + 8]);  // the output inside a larger message
        std::memcpy(owner.get() + 8, it->data(), it->size());
        store.job_done(owner, it->size() + 8, std::string_view(owner.get() + 8, it->size()));
      }
      CHECK(store.jobs_offloaded() == static_cast<std::int64_t>(outputs.size()));
      CHECK(store.jobs_local() == 0);
      store.check_complete();
      stats.push_back(store.calc_stats());
    }
    const std::int64_t n = 150;
    const std::size_t nb = static_cast<std::size_t>(cols.n_bays_max);
    const auto f64_0 = read_f64_column(f, "runs/" + std::string(cols.f64[0]->name), n);
    const auto f64_last = read_f64_column(f, "runs/" + std::string(cols.f64.back()->name), n);
    const auto bays = read_f64_columns(f, "runs/bays/" + std::string(cols.bay[1]->name), n, static_cast<std::int64_t>(nb), 0,
                                       static_cast<std::int64_t>(nb), 16);
    const auto speed = read_f64_column(f, "runs/inputs/drive.speed_m_per_s", n);
    for (std::int64_t run = 0; run < n; ++run) {
      const RunRecord r = record(run);
      const auto i = static_cast<std::size_t>(run);
      CHECK(f64_0[i] == r.f64.front());
      CHECK(f64_last[i] == r.f64.back());
      for (std::size_t b = 0; b < nb; ++b) CHECK(bays[b][i] == r.bays[nb + b]);
      CHECK(speed[i] == r.inputs.back());  // the per-run dispersion's one dimension comes last
    }
    H5Fclose(f);
    fs::remove(path);
  }
  REQUIRE(stats.size() == 2);
  REQUIRE(stats[0].f64.size() == cols.f64.size());
  for (std::size_t k = 0; k < cols.f64.size(); ++k) {
    CHECK(stats[1].f64[k].count == stats[0].f64[k].count);
    CHECK(stats[1].f64[k].max == stats[0].f64[k].max);
    CHECK(stats[1].f64[k].percentiles == stats[0].f64[k].percentiles);
  }
}

TEST_CASE("result store: an error on the write thread reaches the caller, nothing hangs", "[campaign][codec]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const std::string path = (fs::temp_directory_path() / "truss_test_store_thread_error.h5").string();
  fs::remove(path);
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  {
    ResultStore store(f, ctx, StoreOptions{16, 1, true, 1024, true});
    if (store.has_write_thread()) {
      std::string job, out;
      for (std::int64_t run = 0; run < 16; ++run) store.add(test::distinct_record(ctx.columns, run), 0);
      CHECK(store.jobs_pending());  // staged: the chunk completes on the thread
      store.finish_writes();
      REQUIRE(store.take_job(job));
      encode_job_output(job, out);
      std::shared_ptr<char[]> owner(new char[out.size()]);
      std::memcpy(owner.get(), out.data(), out.size());
      store.job_done(owner, out.size(), std::string_view(owner.get(), out.size() / 2));  // cut short: refused on the thread
      CHECK_THROWS_AS(store.finish_writes(), std::runtime_error);
      CHECK_THROWS_AS(store.job_done(owner, out.size(), std::string_view(owner.get(), out.size())), std::runtime_error);
    }
  }
  H5Fclose(f);
  fs::remove(path);
}

// The same feed of results with and without the write thread, and no waiting between the two
// threads: the thread stores records and completes chunks while this one checks records, takes
// jobs, returns their outputs a few steps later (a worker's round trip) and recycles the buffers.
// ThreadSanitizer runs this (store_tsan); here it checks that nothing is lost or changed.
TEST_CASE("result store: records, jobs and outputs crossing the write thread as a campaign does", "[campaign][codec]") {
  const std::int64_t n = 1000;
  const CampaignContext ctx(test::small_campaign("latin_hypercube", n));
  const OutputColumns& cols = ctx.columns;
  const std::string path = (fs::temp_directory_path() / "truss_test_store_cross.h5").string();
  std::vector<StreamedStats> stats;
  for (const bool threaded : {false, true}) {
    INFO((threaded ? "write thread" : "one thread"));
    fs::remove(path);
    const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    {
      ResultStore store(f, ctx, StoreOptions{32, 1, true, 1024, threaded});
      std::deque<std::pair<std::shared_ptr<char[]>, std::size_t>> returning;  // outputs on their way back
      std::int64_t jobs = 0;
      auto step = [&](bool all) {  // jobs taken and encoded; outputs three steps old (or all) returned
        std::string job, out;
        while (store.take_job(job)) {
          encode_job_output(job, out);
          std::shared_ptr<char[]> owner(new char[out.size() + 16]);
          std::memcpy(owner.get() + 16, out.data(), out.size());
          returning.emplace_back(std::move(owner), out.size());
          store.recycle(std::move(job));
          job = std::string();
          ++jobs;
        }
        while (returning.size() > (all ? 0u : 3u)) {
          auto [owner, size] = std::move(returning.front());
          returning.pop_front();
          store.job_done(owner, size + 16, std::string_view(owner.get() + 16, size));
        }
      };
      std::mt19937_64 rng(5);
      std::int64_t run = 0;
      while (run < n) {
        if (rng() % 3 == 0) {  // one of rank 0's own runs
          store.add(test::distinct_record(cols, run++), 1);
        } else {  // a worker's message of 1 to 8 records
          std::vector<std::int64_t> runs;
          for (std::uint64_t k = 1 + rng() % 8; k > 0 && run < n; --k) runs.push_back(run++);
          add_message(store, cols, runs, 1);
        }
        step(false);
      }
      while (store.jobs_pending() || !returning.empty()) step(true);
      CHECK(store.jobs_offloaded() == jobs);
      store.drain_jobs();
      store.check_complete();
      stats.push_back(store.calc_stats());
    }
    const auto last = read_f64_column(f, "runs/" + std::string(cols.f64.back()->name), n);
    const auto status = read_status(f, n);
    for (std::int64_t r = 0; r < n; ++r) {
      const RunRecord rec = test::distinct_record(cols, r);
      CHECK(last[static_cast<std::size_t>(r)] == rec.f64.back());
      CHECK(status[static_cast<std::size_t>(r)] == static_cast<std::int8_t>(rec.status));
    }
    H5Fclose(f);
    fs::remove(path);
  }
  REQUIRE(stats.size() == 2);
  // Which percentiles the kept values resolve depends on when the chunks' summaries were merged
  // (the windows narrow as they come), so it may differ between the two; a resolved one is exact:
  // the one calc_stats finds from all the values (the end's read-back of an unresolved column).
  std::vector<std::uint8_t> use(static_cast<std::size_t>(n));
  std::vector<std::vector<double>> values(cols.f64.size(), std::vector<double>(static_cast<std::size_t>(n)));
  for (std::int64_t r = 0; r < n; ++r) {
    const RunRecord rec = test::distinct_record(cols, r);
    use[static_cast<std::size_t>(r)] = rec.status == truss::sim::RunStatus::ok;
    for (std::size_t k = 0; k < cols.f64.size(); ++k) values[k][static_cast<std::size_t>(r)] = rec.f64[k];
  }
  for (std::size_t k = 0; k < cols.f64.size(); ++k) {
    const Stats exact = calc_stats(values[k], use);
    CHECK(stats[1].f64[k].count == stats[0].f64[k].count);
    CHECK(stats[1].f64[k].mean == stats[0].f64[k].mean);  // chunks combined in run-index order: the same bits
    CHECK(stats[1].f64[k].max == stats[0].f64[k].max);
    for (const StreamedStats& s : stats)
      for (std::size_t q = 0; q < exact.percentiles.size(); ++q)
        CHECK((std::isnan(s.f64[k].percentiles[q]) || s.f64[k].percentiles[q] == exact.percentiles[q]));
  }
}

// The checks stay on the calling thread when the copy moves to the write thread: a repeated run,
// a run out of range, an unknown status and a cut record are refused at once, by add and by
// add_records alike, and are not counted.
TEST_CASE("result store: bad records are refused where they are handed over", "[campaign][codec]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const OutputColumns& cols = ctx.columns;
  const std::string path = (fs::temp_directory_path() / "truss_test_store_refuse.h5").string();
  for (const bool threaded : {false, true}) {
    INFO((threaded ? "write thread" : "one thread"));
    fs::remove(path);
    const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    {
      ResultStore store(f, ctx, StoreOptions{16, 1, true, 1024, threaded});
      store.add(test::distinct_record(cols, 3), 0);
      add_message(store, cols, {4, 5}, 0);
      CHECK_THROWS_WITH(store.add(test::distinct_record(cols, 3), 0), Catch::Contains("run 3 received twice"));
      CHECK_THROWS_WITH(add_message(store, cols, {6, 5}, 0), Catch::Contains("run 5 received twice"));
      CHECK_THROWS_WITH(store.add(test::distinct_record(cols, 40), 0), Catch::Contains("run index 40 out of range"));
      RunRecord bad = test::distinct_record(cols, 7);
      std::string bytes;
      bad.append_bytes(bytes);
      bytes[8] = static_cast<char>(truss::sim::kRunStatusCount);
      CHECK_THROWS_WITH(store.add_bytes(bytes, 0), Catch::Contains("unknown status"));
      bytes.pop_back();
      CHECK_THROWS_WITH(store.add_bytes(bytes, 0), Catch::Contains("is not a run record of this campaign"));
      CHECK(store.n_done() == 4);  // 3, 4, 5 and the 6 of the refused message (checked before the 5)
      CHECK_FALSE(store.has(7));
      CHECK_FALSE(store.has(40 - 1));
      store.finish_writes();
    }
    H5Fclose(f);
    fs::remove(path);
  }
}
