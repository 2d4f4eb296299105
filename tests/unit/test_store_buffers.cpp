// Rank 0's reuse of job buffers (campaign/buffer_pool.hpp): what the pool hands back, and that a
// results file built in reused buffers (holding old bytes) is the one built in fresh buffers.
#include <catch2/catch.hpp>
#include <hdf5.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <filesystem>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "campaign/buffer_pool.hpp"
#include "campaign/campaign.hpp"
#include "campaign/chunk_codec.hpp"
#include "campaign/result_store.hpp"
#include "campaign/run_record.hpp"
#include "campaign_fixtures.hpp"

using namespace truss::campaign;
namespace fs = std::filesystem;

TEST_CASE("buffer pool: the smallest buffer that fits, contents kept, small ones and those past the limit freed",
          "[campaign][store]") {
  BufferPool pool;
  pool.set_limit(5000, 100);
  auto filled = [](std::size_t capacity, char c) {
    std::string s;
    s.reserve(capacity);
    s.assign(capacity / 2, c);
    return s;
  };
  pool.give(filled(3000, 'a'));
  pool.give(filled(1000, 'b'));
  pool.give(filled(50, 'c'));    // under the 100-byte minimum: freed
  pool.give(filled(2000, 'd'));  // 3000 + 1000 + 2000 > 5000: freed
  CHECK(pool.bytes() >= 4000);
  CHECK(pool.bytes() < 6000);
  std::string x = pool.take(900);  // the 1000-byte one, not the 3000
  CHECK(x.capacity() >= 900);
  CHECK(x.capacity() < 3000);
  CHECK(x == std::string(500, 'b'));  // its old contents, for a caller that overwrites them
  std::string y = pool.take(2500);
  CHECK(y == std::string(1500, 'a'));
  CHECK(pool.bytes() == 0);
  std::string z = pool.take(700);  // nothing kept: a new, empty buffer with the room asked for
  CHECK(z.empty());
  CHECK(z.capacity() >= 700);
}

namespace {

// Chunk k of a dataset (n rows, `width` values a row, chunks of `chunk` rows) as a reader of the
// raw chunk sees it: the stored bytes decoded (chunk_codec.hpp, checked against HDF5's own filters
// in test_chunk_codec.cpp).
std::string raw_chunk(hid_t file, const std::string& path, std::int64_t k, std::int64_t chunk, std::size_t width) {
  const hid_t ds = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  REQUIRE(ds >= 0);
  const hsize_t offset[2] = {static_cast<hsize_t>(k * chunk), 0};
  hsize_t size = 0;
  REQUIRE(H5Dget_chunk_storage_size(ds, offset, &size) >= 0);
  std::string stored(size, '\0'), raw;
  std::uint32_t mask = 0;
  REQUIRE(H5Dread_chunk(ds, H5P_DEFAULT, offset, &mask, stored.data()) >= 0);
  H5Dclose(ds);
  decode_chunk(stored, mask, 8, 1, static_cast<std::size_t>(chunk) * width * 8, raw);
  return raw;
}

}  // namespace

TEST_CASE("result store: chunks built in reused job buffers hold the runs' values and zeros past n", "[campaign][store]") {
  // Chunks of 1,024 runs: each dataset chunk is small, so they travel as grouped jobs of about
  // 1 MB, which the pool keeps; 3,000 runs make the last chunk an edge chunk (zeros past n).
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 3000));
  const OutputColumns& cols = ctx.columns;
  const std::int64_t n = 3000, chunk = 1024;
  const auto nb = static_cast<std::size_t>(cols.n_bays_max);
  auto record = [&](std::int64_t run) { return test::distinct_record(cols, run); };
  // Nearly in order, as a campaign's results arrive: chunks complete one after another, so the
  // later ones are built in the buffers of the earlier ones.
  std::vector<std::int64_t> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::mt19937_64 rng(11);
  for (std::size_t b = 0; b < order.size(); b += 200) std::shuffle(order.begin() + b, order.begin() + std::min(b + 200, order.size()), rng);
  // Each job's buffer comes back as the scheduler returns it: overwritten (0xAB) and longer (a
  // work message's run indices and trailer).
  const std::string path = (fs::temp_directory_path() / "truss_test_store_reuse.h5").string();
  const hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  REQUIRE(f >= 0);
  {
    ResultStore store(f, ctx, StoreOptions{chunk, 1, true});
    std::string job, out;
    for (std::int64_t run : order) {
      store.add(record(run), 0);
      while (store.take_job(job)) {
        encode_job_output(job, out);
        store.job_done(out);
        std::fill(job.begin(), job.end(), static_cast<char>(0xAB));
        job.append(264, static_cast<char>(0xAB));
        store.recycle(std::move(job));
        job = std::string();
      }
    }
    store.drain_jobs();
    store.check_complete();
  }
  // Expected raw chunks, built here from the records: values of runs first .. first + rows - 1,
  // then zeros.
  struct Column {
    std::string path;
    std::size_t width;
    std::function<double(const RunRecord&, std::size_t)> value;
  };
  const std::size_t last_bay = (cols.bay.size() - 1) * nb;
  const std::vector<Column> columns = {
      {"runs/" + std::string(cols.f64[0]->name), 1, [](const RunRecord& r, std::size_t) { return r.f64.front(); }},
      {"runs/" + std::string(cols.f64.back()->name), 1, [](const RunRecord& r, std::size_t) { return r.f64.back(); }},
      {"runs/bays/" + std::string(cols.bay.back()->name), nb, [&](const RunRecord& r, std::size_t b) { return r.bays[last_bay + b]; }},
      {"runs/inputs/mast.strut_mass_kg", nb, [](const RunRecord& r, std::size_t b) { return r.inputs[b]; }}};
  for (const Column& c : columns) {
    for (std::int64_t k = 0; k * chunk < n; ++k) {
      INFO(c.path << " chunk " << k);
      std::vector<double> want(static_cast<std::size_t>(chunk) * c.width, 0.0);
      for (std::int64_t i = 0; i < chunk && k * chunk + i < n; ++i) {
        const RunRecord r = record(k * chunk + i);
        for (std::size_t b = 0; b < c.width; ++b) want[static_cast<std::size_t>(i) * c.width + b] = c.value(r, b);
      }
      const std::string raw = raw_chunk(f, c.path, k, chunk, c.width);
      REQUIRE(raw.size() == want.size() * 8);
      CHECK(std::memcmp(raw.data(), want.data(), raw.size()) == 0);
    }
  }
  H5Fclose(f);
  fs::remove(path);
}
