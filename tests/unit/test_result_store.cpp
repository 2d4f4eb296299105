// The results file's chunks encoded outside HDF5 (results/chunk_codec) against HDF5's own filter
// pipeline, and the result store (results/result_store) against the records it was given: in any
// order, across rounds that extend it, with and without compression.
#include <catch2/catch.hpp>

#include <hdf5.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <isa-l/igzip_lib.h>
#include <zlib.h>

#include "campaign_fixtures.hpp"
#include "results/chunk_codec.hpp"
#include "results/chunk_builder.hpp"
#include "results/placement_driver.hpp"
#include "results/read_back.hpp"
#include "results/result_store.hpp"

using namespace truss::campaign;
using namespace truss::results;
namespace fs = std::filesystem;

namespace {

// A file `name` in the temporary folder holding a 1-D dataset "x" of n elements of `type` in one
// chunk, shuffled and deflated at `level`; f(file, dataset) runs on it, then everything is closed.
// Returns the file's path.
template <class F>
std::string write_one_chunk_dataset(const char* name, hid_t type, hsize_t n, int level, F&& f) {
  const std::string path = (fs::temp_directory_path() / name).string();
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
  return path;
}

// The same, the file removed after f.
template <class F>
void with_one_chunk_dataset(hid_t type, hsize_t n, int level, F&& f) {
  fs::remove(write_one_chunk_dataset("truss_test_chunk_codec.h5", type, n, level, std::forward<F>(f)));
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

// HDF5 reading `stored` (mask) back through its own filter pipeline (H5Dwrite_chunk, the file
// closed, then H5Dread): the values a reader of the file sees. (Read before the file is closed,
// HDF5 1.10 applies the filters to a dataset's single chunk as if its mask were 0.)
std::string hdf5_read_back(const std::string& stored, std::uint32_t mask, hid_t type, std::size_t es, std::size_t raw_bytes,
                           int level) {
  std::string back(raw_bytes, '\0');
  const std::string path = write_one_chunk_dataset("truss_test_chunk_read_back.h5", type, raw_bytes / es, level,
                                                   [&](hid_t, hid_t ds) {
                                                     const hsize_t offset = 0;
                                                     CHECK(H5Dwrite_chunk(ds, H5P_DEFAULT, mask, &offset, stored.size(),
                                                                          stored.data()) >= 0);
                                                   });
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t ds = H5Dopen2(file, "x", H5P_DEFAULT);
  CHECK(H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, back.data()) >= 0);
  H5Dclose(ds);
  H5Fclose(file);
  fs::remove(path);
  return back;
}

std::string random_doubles(std::size_t n, bool smooth, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(1.25, smooth ? 1e-3 : 1e3);
  std::vector<double> v(n);
  for (auto& x : v) x = g(rng);
  return std::string(reinterpret_cast<const char*>(v.data()), n * 8);
}

// n doubles whose byte j (plane j after the shuffle) is byte(j, rng), from a generator seeded `seed`.
template <class F>
std::vector<unsigned char> chunk_of_planes(std::size_t n, unsigned seed, F byte) {
  std::mt19937_64 rng(seed);
  std::vector<unsigned char> raw(8 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < 8; ++j) raw[8 * i + j] = static_cast<unsigned char>(byte(j, rng));
  return raw;
}

// `raw` (whole doubles) encoded at level 1 with every filter applied, checked against inflaters
// independent of the encoder: zlib's own (uncompress) must give the chunk shuffled as HDF5's
// shuffle filter defines it (byte j of element i at j * n + i), and HDF5 must read the chunk back.
// Returns the stream; `shuffled` gets the shuffled chunk.
std::string encode_checked(const std::vector<unsigned char>& raw, std::vector<unsigned char>& shuffled) {
  const std::size_t n = raw.size() / 8;
  shuffled.assign(raw.size(), 0);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < 8; ++j) shuffled[j * n + i] = raw[8 * i + j];
  const std::string chunk(raw.begin(), raw.end());
  std::string mine;
  ChunkCodec codec;
  REQUIRE(codec.encode(chunk, 8, 1, mine) == 0);
  std::vector<unsigned char> inflated(raw.size());
  uLongf len = inflated.size();
  REQUIRE(uncompress(inflated.data(), &len, reinterpret_cast<const Bytef*>(mine.data()), mine.size()) == Z_OK);
  CHECK(len == inflated.size());
  CHECK(inflated == shuffled);
  CHECK(hdf5_read_back(mine, 0, H5T_NATIVE_DOUBLE, 8, chunk.size(), 1) == chunk);
  return mine;
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
                        {random_doubles(1003, true, 4), H5T_NATIVE_DOUBLE, 8},  // not whole blocks of eight
                        {status, H5T_NATIVE_INT8, 1}};                            // statuses: shuffle is a no-op
  ChunkCodec codec;
  for (int level : {1, 2, 6}) {  // ISA-L levels 1, 2 and 3
    for (const Case& c : cases) {
      std::uint32_t hdf5_mask = 99;
      const std::string hdf5 = hdf5_filtered_chunk(c.raw, c.type, c.es, level, hdf5_mask);
      std::string mine;
      const std::uint32_t mask = codec.encode(c.raw, c.es, level, mine);
      // The deflate stream is ISA-L's, not zlib's: not the same bytes, but HDF5 inflates it to
      // the same values and the same filters are skipped (HDF5's buffer rule). Size: both are
      // DEFLATE at the same level with different match finders and block choices; where zlib sends
      // the noise planes of the low mantissa bytes as stored blocks, ISA-L codes them with Huffman
      // codes a few % larger. Chunk by chunk within 5 % of zlib's (+64 bytes of framing for tiny
      // outputs) -- measured 0.93 to 1.045 of zlib's, and 0.58 to 1.21 only on the 4 kB status
      // chunk (tens of bytes).
      CHECK(mask == hdf5_mask);
      CHECK(hdf5_read_back(mine, mask, c.type, c.es, c.raw.size(), level) == c.raw);
      INFO("level " << level << ": " << mine.size() << " bytes against zlib's " << hdf5.size());
      CHECK(mine.size() <= hdf5.size() + 5 * hdf5.size() / 100 + 64);
    }
  }
  std::string plain;
  CHECK(codec.encode(cases[0].raw, 8, 0, plain) == 0);
  CHECK(plain == cases[0].raw);  // level 0: no filter, the raw bytes
}

// Every byte plane is deflated, noise too: a chunk of 4,096 doubles of narrow spread whose 6 low
// planes are noise (bytes of a random generator) and whose 2 high planes are one value each. Its
// stream is read by zlib's own inflater (uncompress, an implementation independent of ISA-L) and by
// HDF5; DEFLATE cannot shrink the noise, but must not grow it past its stored size (RFC 1951 stored
// blocks: 5 bytes of header per 65,535 bytes) by more than its block headers and Huffman tables
// (1 %), while the two constant planes take almost nothing.
TEST_CASE("chunk codec: noise planes deflated to no more than their size, the rest to almost nothing",
          "[campaign][codec]") {
  const std::size_t n = 4096;
  std::vector<unsigned char> shuffled;
  const auto raw = chunk_of_planes(n, 7, [](std::size_t j, std::mt19937_64& rng) {
    return j < 6 ? rng() : j == 6 ? 0xf4 : 0x3f;
  });
  const std::string mine = encode_checked(raw, shuffled);
  const std::size_t noise = 6 * n;
  CHECK(mine.size() < noise + noise / 100 + 600);
}

// Constant chunks are encoded once per value, size and level: each encoding, reused or not, must
// inflate (zlib's uncompress) to its own chunk, shuffled. NaN, then 0.0, then NaN again, then
// int64 30 (elements of the same 8 bytes' size), at two sizes and two levels.
TEST_CASE("chunk codec: constant chunks, each its own stream", "[campaign][codec]") {
  auto constant = [](double v, std::size_t n) {
    std::string raw(8 * n, '\0');
    for (std::size_t i = 0; i < n; ++i) std::memcpy(raw.data() + 8 * i, &v, 8);
    return raw;
  };
  std::int64_t thirty = 30;
  double as_double = 0.0;
  std::memcpy(&as_double, &thirty, 8);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ChunkCodec codec;  // one codec, as one store: its memo of constant chunks serves the repeats
  for (int level : {1, 6})
    for (std::size_t n : {std::size_t{4096}, std::size_t{1250}})
      for (double v : {nan, 0.0, nan, as_double}) {
        const std::string raw = constant(v, n);
        std::string mine;
        REQUIRE(codec.encode(raw, 8, level, mine) == 0);
        std::string inflated(raw.size(), '\1');
        uLongf len = inflated.size();
        REQUIRE(uncompress(reinterpret_cast<Bytef*>(inflated.data()), &len, reinterpret_cast<const Bytef*>(mine.data()),
                           mine.size()) == Z_OK);
        std::string shuffled(raw.size(), '\0');
        for (std::size_t i = 0; i < n; ++i)
          for (std::size_t j = 0; j < 8; ++j) shuffled[j * n + i] = raw[8 * i + j];
        INFO("level " << level << ", " << n << " elements of " << v);
        CHECK(len == raw.size());
        CHECK(inflated == shuffled);
        CHECK(mine.size() < 200);
      }
}

// Reading a finished file back (read_columns.cpp) decodes the stored chunks itself: every chunk
// HDF5 reads must decode to what HDF5's own pipeline (zlib's inflate, its unshuffle) reads from the
// same stored bytes and mask -- zlib's streams and the codec's, each filter skipped or not, the
// unfiltered pipeline -- and a damaged stream is refused, not decoded to other values.
TEST_CASE("chunk codec: decode reads every chunk as HDF5's own pipeline does", "[campaign][codec]") {
  ChunkCodec codec, decoder;
  std::string raw_status(4096, '\0');
  for (std::size_t i = 0; i < raw_status.size(); ++i) raw_status[i] = static_cast<char>(i % 97 == 0 ? 3 : 0);
  struct Case {
    std::string raw;
    hid_t type;
    std::size_t es;
  };
  const Case cases[] = {{random_doubles(4096, true, 11), H5T_NATIVE_DOUBLE, 8},
                        {random_doubles(2050 * 30, false, 12), H5T_NATIVE_DOUBLE, 8},
                        {random_doubles(1, true, 13), H5T_NATIVE_DOUBLE, 8},  // one element: shuffle is a copy
                        {raw_status, H5T_NATIVE_INT8, 1}};
  std::string out;
  for (const Case& c : cases)
    for (int level : {1, 6}) {
      INFO(c.raw.size() << " bytes, level " << level);
      std::uint32_t zlib_mask = 99;
      const std::string by_zlib = hdf5_filtered_chunk(c.raw, c.type, c.es, level, zlib_mask);
      std::string mine;
      const std::uint32_t mine_mask = codec.encode(c.raw, c.es, level, mine);
      std::string shuffled, deflated_only;
      // Stored forms with a filter skipped: the shuffled bytes (deflate skipped), and the raw bytes
      // deflated without a shuffle (shuffle skipped: a zlib stream of raw, from zlib's compress2).
      std::vector<unsigned char> sh(c.raw.size());
      for (std::size_t i = 0; i < c.raw.size() / c.es; ++i)
        for (std::size_t j = 0; j < c.es; ++j) sh[j * (c.raw.size() / c.es) + i] = static_cast<unsigned char>(c.raw[i * c.es + j]);
      shuffled.assign(sh.begin(), sh.end());
      uLongf len = compressBound(c.raw.size());
      deflated_only.assign(len, '\0');
      REQUIRE(compress2(reinterpret_cast<Bytef*>(deflated_only.data()), &len, reinterpret_cast<const Bytef*>(c.raw.data()),
                        c.raw.size(), level) == Z_OK);
      deflated_only.resize(len);
      const std::pair<std::string, std::uint32_t> stored[] = {{by_zlib, zlib_mask}, {mine, mine_mask},
                                                              {shuffled, kDeflateSkipped},
                                                              {deflated_only, kShuffleSkipped},
                                                              {c.raw, kShuffleSkipped | kDeflateSkipped}};
      for (const auto& [bytes, mask] : stored) {
        INFO("mask " << mask);
        const std::string hdf5 = hdf5_read_back(bytes, mask, c.type, c.es, c.raw.size(), level);
        REQUIRE(hdf5 == c.raw);  // the reference reads the raw chunk back
        decoder.decode(bytes, mask, true, c.es, c.raw.size(), out);
        CHECK(out == hdf5);
      }
      // A damaged stream: a byte of the DEFLATE data changed (the Adler-32 catches what inflates),
      // the stream cut short, a size other than the chunk's.
      std::string bad = mine;
      bad[bad.size() / 2] = static_cast<char>(bad[bad.size() / 2] ^ 0x5a);
      CHECK_THROWS_AS(decoder.decode(bad, mine_mask, true, c.es, c.raw.size(), out), std::runtime_error);
      CHECK_THROWS_AS(decoder.decode(mine.substr(0, mine.size() - 5), mine_mask, true, c.es, c.raw.size(), out),
                      std::runtime_error);
      CHECK_THROWS_AS(decoder.decode(mine, mine_mask, true, c.es, c.raw.size() + c.es, out), std::runtime_error);
    }
  decoder.decode(cases[0].raw, 0, false, 8, cases[0].raw.size(), out);  // no filter: the raw bytes
  CHECK(out == cases[0].raw);
  CHECK_THROWS_AS(decoder.decode(cases[0].raw, 0, false, 8, cases[0].raw.size() - 8, out), std::runtime_error);
}

namespace {

// A results file read back: every dataset, through HDF5's own filters.
struct StoreFile {
  std::string path;
  hid_t file;
  explicit StoreFile(const std::string& p) : path(p), file(H5Fopen(p.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT)) {
    REQUIRE(file >= 0);
  }
  ~StoreFile() { H5Fclose(file); }
  std::vector<std::int64_t> i64(const std::string& ds, std::int64_t n) const {
    std::vector<std::int64_t> v(static_cast<std::size_t>(n));
    const hid_t d = H5Dopen2(file, ds.c_str(), H5P_DEFAULT);
    REQUIRE(H5Dread(d, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
    H5Dclose(d);
    return v;
  }
  std::vector<double> f64(const std::string& ds, std::int64_t values) const {
    std::vector<double> v(static_cast<std::size_t>(values));
    const hid_t d = H5Dopen2(file, ds.c_str(), H5P_DEFAULT);
    REQUIRE(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) >= 0);
    H5Dclose(d);
    return v;
  }
  mutable std::int64_t null_strings = 0;  // of the last strings() read
  std::vector<std::string> strings(const std::string& ds, std::int64_t n) const {
    std::vector<char*> p(static_cast<std::size_t>(n));
    const hid_t d = H5Dopen2(file, ds.c_str(), H5P_DEFAULT);
    const hid_t t = H5Dget_type(d);
    REQUIRE(H5Dread(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, p.data()) >= 0);
    std::vector<std::string> out;
    for (const char* q : p) out.push_back(q ? q : "");  // NULL: an unwritten chunk (the fill value)
    null_strings = static_cast<std::int64_t>(std::count(p.begin(), p.end(), nullptr));
    const hid_t space = H5Dget_space(d);
    H5Dvlen_reclaim(t, space, H5P_DEFAULT, p.data());
    H5Sclose(space);
    H5Tclose(t);
    H5Dclose(d);
    return out;
  }
  // The stored (filtered) bytes and mask of every chunk of dataset `ds`, in chunk order.
  std::vector<std::pair<std::string, std::uint32_t>> chunks(const std::string& ds) const {
    std::vector<std::pair<std::string, std::uint32_t>> out;
    const hid_t d = H5Dopen2(file, ds.c_str(), H5P_DEFAULT);
    const hid_t space = H5Dget_space(d);
    hsize_t n = 0;
    REQUIRE(H5Dget_num_chunks(d, space, &n) >= 0);
    for (hsize_t k = 0; k < n; ++k) {
      hsize_t offset[2] = {0, 0}, size = 0;
      unsigned mask = 0;
      haddr_t addr = 0;
      REQUIRE(H5Dget_chunk_info(d, space, k, offset, &mask, &addr, &size) >= 0);
      std::string bytes(size, '\0');
      std::uint32_t m = 0;
      REQUIRE(H5Dread_chunk(d, H5P_DEFAULT, offset, &m, bytes.data()) >= 0);
      out.emplace_back(std::move(bytes), m);
    }
    H5Sclose(space);
    H5Dclose(d);
    return out;
  }
};

// A results file written as a campaign writes it, in one process: the chunks built by `n_builders`
// builders (chunk k by builder k mod n_builders, as the owners on several ranks), reported to the
// store, which places them, and their bytes written where they were placed, as an owner writes them.
struct Campaign {
  std::string path;
  PlacementState placement;
  hid_t file = -1;
  std::unique_ptr<ResultStore> store;
  std::vector<std::unique_ptr<ChunkBuilder>> builders;
  std::vector<RoundPart> parts;
  int fd = -1;
  std::int64_t chunk;
  const RecordLayout& L;
  ChunkStats stats{L};  // the statistics rank's, here in the same process
  std::vector<std::unique_ptr<ChunkStats>> shards;  // statistics ranks' ranges of the columns, if any
  Campaign(const std::string& name, const RecordLayout& layout, const StoreOptions& opts, int n_builders,
           std::vector<std::size_t> observed = {}, std::size_t metadata_cache = 0)
      : path((fs::temp_directory_path() / name).string()), chunk(opts.chunk_runs), L(layout) {
    fs::remove(path);
    const hid_t fapl = make_placement_fapl(placement);
    if (metadata_cache > 0) {  // a small metadata cache: HDF5 writes its global heap out at any time
      H5AC_cache_config_t c;
      c.version = H5AC__CURR_CACHE_CONFIG_VERSION;
      REQUIRE(H5Pget_mdc_config(fapl, &c) >= 0);
      c.set_initial_size = true;
      c.initial_size = c.min_size = c.max_size = metadata_cache;
      c.incr_mode = H5C_incr__off;
      c.flash_incr_mode = H5C_flash_incr__off;
      c.decr_mode = H5C_decr__off;
      REQUIRE(H5Pset_mdc_config(fapl, &c) >= 0);
    }
    file = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    REQUIRE(file >= 0);
    store = std::make_unique<ResultStore>(file, placement, L, opts);
    for (int b = 0; b < n_builders; ++b) builders.push_back(std::make_unique<ChunkBuilder>(L, opts, observed));
    fd = ::open(path.c_str(), O_WRONLY);
    REQUIRE(fd >= 0);
  }
  ~Campaign() {
    if (fd >= 0) ::close(fd);
    store.reset();
    if (file >= 0) H5Fclose(file);
    fs::remove(path);
  }
  // One round of n runs, each run's distinct record added (session 0).
  void add_round_of_distinct(std::int64_t n) {
    round(0, 0, n);
    for (std::int64_t r = 0; r < n; ++r) add(test::distinct_record(L, r), 0);
  }
  void round(std::int64_t r, std::int64_t first, std::int64_t n) {
    store->extend(first + n);
    for (auto& b : builders) b->add_round(r, first, n);
  }
  ChunkBuilder& builder_of(std::int64_t run) { return *builders[static_cast<std::size_t>(run / chunk) % builders.size()]; }
  void add(const std::string& rec, std::int64_t session) {
    const RecordView v(rec, L);
    builder_of(v.run()).add(v, session);
    pump();
  }
  // What the builders produced: parts kept, complete chunks encoded, placed and written.
  void pump() {
    for (auto& b : builders) {
      while (auto p = b->pop_part()) parts.push_back(std::move(*p));
      while (auto k = b->pop_complete()) {
        if (!stats.seeded()) stats.seed(b->first_windows(*k));
        for (auto& sh : shards)
          if (!sh->seeded()) sh->seed(b->first_windows(*k, sh->columns()));
        EncodedChunk e;
        while (!b->encode_step(*k, stats.windows(), e)) {
        }
        const std::vector<ChunkAddress> at = store->place(e.report);
        for (auto& sh : shards) {
          const ColumnRange r = sh->columns();
          sh->merge(e.report.index, {e.report.summaries.begin() + static_cast<std::ptrdiff_t>(r.begin),
                                     e.report.summaries.begin() + static_cast<std::ptrdiff_t>(r.end)});
        }
        stats.merge(e.report.index, e.report.summaries);
        for (std::size_t d = 0; d < at.size(); ++d)
          REQUIRE(::pwrite(fd, e.bytes[d].data(), e.bytes[d].size(), static_cast<off_t>(at[d].offset)) ==
                  static_cast<ssize_t>(e.bytes[d].size()));
      }
    }
  }
  // Every round planned: the last chunks, the file closed. The statistics.
  StreamedStats close() {
    for (auto& b : builders) b->end_rounds();
    pump();
    store->finish();
    StreamedStats s = stats.calc_stats((store->n_runs() + chunk - 1) / chunk);
    store.reset();
    H5Fclose(file);
    file = -1;
    return s;
  }
};

// Every run's values in the file against distinct_record's: each f64 cell of each field at its
// row and column, the integers, the statuses, the messages, the sessions.
void check_file(const StoreFile& f, const RecordLayout& L, std::int64_t n, std::int64_t session_of_odd,
                std::int64_t round_runs = 40) {
  const auto status = read_status(f.file, n);
  const auto message = f.strings("runs/message", n);
  const auto session = f.i64("timing/session", n);
  const auto round = f.i64("runs/round", n);
  for (std::int64_t r = 0; r < n; ++r) {
    const auto i = static_cast<std::size_t>(r);
    CHECK(status[i] == (test::stalls(r) ? 2 : 0));
    CHECK(message[i] == (test::stalls(r) ? fmt::format("stall: run {}", r) : ""));
    CHECK(session[i] == (r % 2 ? session_of_odd : 0));
    CHECK(round[i] == r / round_runs);
  }
  int cell = 0;
  for (std::size_t k = RecordLayout::kWallTime + 1; k < L.fields().size(); ++k) {
    const Field& fd = L.fields()[k];
    const std::string path = std::string(group_path(fd.group)) + "/" + fd.name;
    if (fd.type == ValueType::i64) {
      const auto v = f.i64(path, n);
      for (std::int64_t r = 0; r < n; ++r) CHECK(v[static_cast<std::size_t>(r)] == r * 100 + static_cast<std::int64_t>(k));
      continue;
    }
    // Read back as the statistics do (the codec's decoder) and as HDF5 reads it (its filters);
    // rows out of order and repeated, as the failure samples read them.
    const auto cols = read_f64_columns(f.file, path, n, 0, fd.width);
    const auto by_hdf5 = f.f64(path, n * fd.width);
    std::vector<std::int64_t> picked;
    for (std::int64_t r = n - 1; r >= 0; r -= 3) picked.push_back(r);
    picked.push_back(n - 1);
    picked.push_back(0);
    const auto rows = read_f64_rows(f.file, path, picked);
    REQUIRE(rows.size() == picked.size() * static_cast<std::size_t>(fd.width));
    for (int j = 0; j < fd.width; ++j, ++cell) {
      for (std::int64_t r = 0; r < n; ++r) {
        INFO(path << " column " << j << " run " << r);
        CHECK(cols[static_cast<std::size_t>(j)][static_cast<std::size_t>(r)] == test::cell_value(r, cell));
        CHECK(by_hdf5[static_cast<std::size_t>(r * fd.width + j)] == test::cell_value(r, cell));
      }
      for (std::size_t k = 0; k < picked.size(); ++k)
        CHECK(rows[k * static_cast<std::size_t>(fd.width) + static_cast<std::size_t>(j)] == test::cell_value(picked[k], cell));
    }
    CHECK_THROWS_AS(read_f64_rows(f.file, path, {n}), std::out_of_range);
    CHECK_THROWS_AS(read_f64_columns(f.file, path, n, fd.width, 1), std::out_of_range);
  }
}

}  // namespace

// The chunk rule as docs/hdf5-schema.md states it: chunks of 1,024 to 4,096 runs, never longer
// than the campaign, and at least 8 of them while 4,096-run chunks would be fewer (so that writing
// overlaps the runs); checked on every size up to 70,000 runs and a few larger ones.
TEST_CASE("result store: chunks of clamp(n / 8, 1024, 4096) runs, at most n", "[campaign][store]") {
  std::vector<std::int64_t> sizes;
  for (std::int64_t n = 1; n <= 70000; ++n) sizes.push_back(n);
  for (std::int64_t n : {std::int64_t{1} << 20, std::int64_t{1000000007}}) sizes.push_back(n);
  int bad = 0;
  for (const std::int64_t n : sizes) {
    const std::int64_t c = find_chunk_runs(n), chunks = (n + c - 1) / c;
    const bool ok = c >= 1 && c <= n && c <= 4096 && (c >= 1024 || c == n) &&
                    (chunks >= 8 || c == 1024 || c == n) && (c == 4096 || chunks <= 9 || c == 1024);
    bad += !ok;
    if (!ok && bad < 5) FAIL_CHECK("n " << n << ": chunks of " << c << " runs, " << chunks << " of them");
  }
  CHECK(bad == 0);
  CHECK(find_chunk_runs(10000) == 1250);  // the shipped Table-1 campaign: 8 chunks
}

// /runs/message holds the failed runs' messages: with chunks of 2 runs and a stall (with its message)
// at every run r % 7 == 3, chunks {2k, 2k+1} without such a run stay unwritten, and every row but
// a stall's reads back as the fill value (a NULL string in C, "" in h5py).
TEST_CASE("result store: a chunk of runs without a message is not written", "[campaign][store]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const RecordLayout& L = ctx.record;
  const std::int64_t n = 40;
  Campaign c("truss_test_store_messages.h5", L, StoreOptions{2, 1}, 2);
  c.add_round_of_distinct(n);
  c.close();
  std::int64_t with_message = 0, nulls = 0;
  for (std::int64_t k = 0; k < n / 2; ++k) with_message += test::stalls(2 * k) || test::stalls(2 * k + 1);
  for (std::int64_t r = 0; r < n; ++r) nulls += !test::stalls(r);  // only failed runs' messages are written
  const StoreFile f(c.path);
  const auto message = f.strings("runs/message", n);
  CHECK(f.null_strings == nulls);
  for (std::int64_t r = 0; r < n; ++r)
    CHECK(message[static_cast<std::size_t>(r)] == (test::stalls(r) ? fmt::format("stall: run {}", r) : ""));
  CHECK(static_cast<std::int64_t>(f.chunks("runs/message").size()) == with_message);  // 6 of the 20 chunks
}

// Records in any order, over rounds that extend the datasets (chunks of 16 straddle the rounds),
// their chunks built by 1 or 3 builders (ranks): every value at its row, the same chunk bytes
// whoever built them, every run in exactly one round part with its status and observed output,
// and the statistics equal to calc_stats of each whole column.
TEST_CASE("result store: chunks built anywhere, in any order, over rounds: the same file", "[campaign][store]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const RecordLayout& L = ctx.record;
  const int force = L.find_output("peak_drive_force_N");
  int force_cell = 0;  // peak_drive_force_N's cell among the float64 cells of a record
  for (int i = RecordLayout::kWallTime + 1; i < force; ++i)
    force_cell += L.fields()[static_cast<std::size_t>(i)].type == ValueType::f64 ? L.fields()[static_cast<std::size_t>(i)].width : 0;
  for (const int level : {1, 0}) {
    INFO("compression " << level);
    const std::int64_t n = 110;  // rounds of 40, 40 and 30 runs
    std::map<int, std::map<std::string, std::vector<std::pair<std::string, std::uint32_t>>>> bytes;
    for (const int n_builders : {1, 3}) {
      INFO(n_builders << " builders");
      Campaign c(fmt::format("truss_test_store_{}.h5", n_builders), L, StoreOptions{16, level}, n_builders,
                 {static_cast<std::size_t>(force)});
      std::mt19937_64 rng(3 + static_cast<unsigned>(n_builders));
      for (std::int64_t first = 0; first < n; first += 40) {
        const std::int64_t end = std::min(n, first + 40);
        c.round(first / 40, first, end - first);
        CHECK(c.store->n_runs() == end);
        std::vector<std::int64_t> runs;
        for (std::int64_t r = first; r < end; ++r) runs.push_back(r);
        std::shuffle(runs.begin(), runs.end(), rng);
        for (std::int64_t r : runs) c.add(test::distinct_record(L, r, r / 40), r % 2 ? 4 : 0);
      }
      CHECK_THROWS_WITH(c.add(test::distinct_record(L, 5), 0), Catch::Contains("run 5 received twice"));
      CHECK_THROWS_WITH(c.add(test::distinct_record(L, n + 5, 2), 0),
                        Catch::Contains("a record of run 115 in round 2, which is not one of its runs"));
      const StreamedStats stats = c.close();
      // Round parts: each run once, in its round, with its status and the observed output.
      std::vector<int> seen(static_cast<std::size_t>(n), 0);
      for (const RoundPart& p : c.parts)
        for (std::int64_t i = 0; i < p.size(); ++i) {
          const std::int64_t r = p.first_run + i;
          ++seen[static_cast<std::size_t>(r)];
          CHECK(p.round == r / 40);
          CHECK(p.status[static_cast<std::size_t>(i)] == (test::stalls(r) ? 2 : 0));
          CHECK(p.outputs.at(0)[static_cast<std::size_t>(i)] == test::cell_value(r, force_cell));
        }
      CHECK(std::all_of(seen.begin(), seen.end(), [](int k) { return k == 1; }));
      const StoreFile f(c.path);
      check_file(f, L, n, 4);
      for (const Field& fd : L.fields()) {
        const std::string ds = std::string(group_path(fd.group)) + "/" + fd.name;
        bytes[n_builders][ds] = f.chunks(ds);
        CHECK(bytes[n_builders][ds].size() == 7);  // 110 rows in chunks of 16
      }
      bytes[n_builders]["timing/session"] = f.chunks("timing/session");
      // The streamed statistics: exact against calc_stats of each whole column (ok runs only).
      std::vector<std::uint8_t> use(static_cast<std::size_t>(n));
      for (std::int64_t r = 0; r < n; ++r) use[static_cast<std::size_t>(r)] = !test::stalls(r);
      const auto col = read_f64_column(f.file, "runs/peak_drive_force_N", n);
      const truss::statistics::Stats exact = truss::statistics::calc_stats(col, use);
      int j = 0;  // its index among the float64 outputs
      for (int i = 0; i < force; ++i) {
        const Field& fd = L.fields()[static_cast<std::size_t>(i)];
        j += fd.statistics && fd.scale == Scale::none;
      }
      const truss::statistics::Stats& s = stats.f64[static_cast<std::size_t>(j)];
      CHECK(s.count == exact.count);
      CHECK(s.min == exact.min);
      CHECK(s.max == exact.max);
      CHECK(s.mean == Approx(exact.mean).epsilon(1e-14));
      for (std::size_t q = 0; q < exact.percentiles.size(); ++q)
        CHECK((!stats.f64_resolved[static_cast<std::size_t>(j)] || s.percentiles[q] == exact.percentiles[q]));
    }
    CHECK(bytes[1] == bytes[3]);  // every chunk's stored bytes, whoever built it
  }
}

TEST_CASE("result store: a chunk is placed once; the end needs every chunk", "[campaign][store]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const RecordLayout& L = ctx.record;
  Campaign c("truss_test_store_missing.h5", L, StoreOptions{16, 1}, 1);
  c.round(0, 0, 20);
  for (std::int64_t r = 0; r < 20; ++r)
    if (r != 17) c.add(test::distinct_record(L, r), 0);
  CHECK(c.store->chunks_placed() == 1);  // chunk 0 is complete; chunk 1 misses run 17
  for (auto& b : c.builders) b->end_rounds();
  c.pump();
  CHECK_THROWS_WITH(c.store->finish(), Catch::Contains("1 of 2 chunks placed"));
  // Another builder's report of chunk 0, or of a chunk of other rows: refused.
  ChunkBuilder again(L, StoreOptions{16, 1}, {});
  again.add_round(0, 0, 20);
  for (std::int64_t r = 0; r < 16; ++r) again.add(RecordView(test::distinct_record(L, r), L), 0);
  EncodedChunk e;
  const std::int64_t k = again.pop_complete().value();
  while (!again.encode_step(k, c.stats.windows(), e)) {
  }
  CHECK_THROWS_WITH(c.store->place(e.report), Catch::Contains("chunk 0 placed twice"));
  e.report.index = 1;
  CHECK_THROWS_WITH(c.store->place(e.report), Catch::Contains("a report of chunk 1 with 16 rows"));
  CHECK_THROWS_AS(ResultStore(c.file, c.placement, L, StoreOptions{0, 1}), std::invalid_argument);
}

// The global heap (the failed runs' messages) is raw data to HDF5's file driver, and HDF5 writes it
// out whenever its metadata cache makes room, also while a chunk is being placed: with a metadata
// cache of 64 kB, 3,000 runs in chunks of 16, every seventh run a stall with its message, each
// chunk's bytes are where the store placed them and every message reads back.
// The statistics rank's side: the chunks' summaries merged once each, after the first windows, and
// the statistics to rank 0 as bytes that read back bit for bit (NaN, -0.0 and the unresolved flags
// included), since rank 0 writes /stats from them.
TEST_CASE("statistics rank: summaries merged once each; the statistics travel bit for bit", "[campaign][store]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const RecordLayout& L = ctx.record;
  Campaign c("truss_test_store_stats_rank.h5", L, StoreOptions{16, 1}, 2);
  c.add_round_of_distinct(40);
  CHECK(c.stats.merged() == 2);  // chunks 0 and 1; chunk 2 (8 rows) completes at the end
  // A summary of chunk 0 again, another count of summaries, or the statistics of 4 chunks: refused.
  ChunkBuilder again(L, StoreOptions{16, 1}, {});
  again.add_round(0, 0, 40);
  for (std::int64_t r = 0; r < 16; ++r) again.add(RecordView(test::distinct_record(L, r), L), 0);
  EncodedChunk e;
  const std::int64_t k = again.pop_complete().value();
  while (!again.encode_step(k, c.stats.windows(), e)) {
  }
  CHECK_THROWS_WITH(c.stats.merge(0, e.report.summaries), Catch::Contains("chunk 0 merged twice"));
  e.report.summaries.pop_back();
  CHECK_THROWS_WITH(c.stats.merge(3, e.report.summaries), Catch::Contains("summaries for"));
  CHECK_THROWS_WITH(c.stats.calc_stats(4), Catch::Contains("miss a chunk"));
  ChunkStats fresh(L);
  CHECK_THROWS_WITH(fresh.merge(0, e.report.summaries), Catch::Contains("before the first windows"));

  c.close();
  StatsPart s = c.stats.calc_part(3);
  REQUIRE(s.stats.size() > 3);
  s.stats[0].mean = -0.0;  // values whose bits a careless copy would change
  s.stats[0].percentiles[2] = std::numeric_limits<double>::quiet_NaN();
  s.resolved[0] = 0;
  s.stats.back().std = -std::numeric_limits<double>::infinity();
  s.merge_cpu_s = 0.125;
  const std::string bytes = to_bytes(s);
  const StatsPart back = read_stats_part(bytes);
  CHECK(to_bytes(back) == bytes);
  CHECK(std::signbit(back.stats[0].mean));
  CHECK(std::isnan(back.stats[0].percentiles[2]));
  CHECK(back.resolved == s.resolved);
  CHECK(back.kept_values == s.kept_values);
  CHECK(back.first == 0);
  CHECK(back.merge_cpu_s == 0.125);
  REQUIRE(back.stats.size() == s.stats.size());
  for (std::size_t k = 0; k < s.stats.size(); ++k) {
    CHECK(back.stats[k].count == s.stats[k].count);
    CHECK(std::memcmp(&back.stats[k].max, &s.stats[k].max, 8) == 0);
  }
  CHECK_THROWS_AS(read_stats_part(bytes.substr(0, bytes.size() - 1)), std::runtime_error);
  CHECK_THROWS_AS(read_stats_part(bytes + "x"), std::runtime_error);
}

// Statistics ranks (engine.hpp): S ranks each merging a contiguous range of the columns, their
// parts assembled on rank 0, give what one rank merging every column gives, bit for bit.
TEST_CASE("statistics ranks: ranges of the columns, their parts assembled as one rank's", "[campaign][store]") {
  // The ranges by hand: 10 columns on 3 ranks from rank 1 are 3, 3 and 4 columns, in order.
  const StatsRanks three{1, 3};
  CHECK(three.find_columns(1, 10) == ColumnRange{0, 3});
  CHECK(three.find_columns(2, 10) == ColumnRange{3, 6});
  CHECK(three.find_columns(3, 10) == ColumnRange{6, 10});
  CHECK(!three.holds(0));
  CHECK(three.holds(3));
  CHECK(!three.holds(4));
  for (int count = 1; count <= 9; ++count) {  // every column once, sizes within one of each other
    const StatsRanks r{1, count};
    std::size_t next = 0, lo = 100, hi = 0;
    for (int rank = 1; rank <= count; ++rank) {
      const ColumnRange c = r.find_columns(rank, 9);
      CHECK(c.begin == next);
      next = c.end;
      lo = std::min(lo, c.size());
      hi = std::max(hi, c.size());
    }
    CHECK(next == 9);
    CHECK(hi - lo <= 1);
  }

  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const RecordLayout& L = ctx.record;
  Campaign c("truss_test_store_stats_ranks.h5", L, StoreOptions{16, 1}, 2);
  const std::size_t n_stats = ChunkColumns(L).n_stats;
  REQUIRE(n_stats > 3);
  const StatsRanks ranks{1, 3};
  for (int rank = 1; rank <= 3; ++rank)
    c.shards.push_back(std::make_unique<ChunkStats>(L, ranks.find_columns(rank, n_stats)));
  c.add_round_of_distinct(40);
  // Each range's windows are the slice of one rank's (a column's statistics are its own).
  const auto all = c.stats.windows();
  for (const auto& sh : c.shards) {
    const auto w = sh->windows();
    REQUIRE(w.size() == sh->columns().size());
    for (std::size_t k = 0; k < w.size(); ++k)
      for (std::size_t t = 0; t < w[k].size(); ++t) {
        CHECK(w[k][t].lo == all[sh->columns().begin + k][t].lo);
        CHECK(w[k][t].hi == all[sh->columns().begin + k][t].hi);
      }
  }
  const StreamedStats one = c.close();
  std::vector<StatsPart> parts;
  for (int i : {2, 0, 1}) parts.push_back(read_stats_part(to_bytes(c.shards[static_cast<std::size_t>(i)]->calc_part(3))));
  const StreamedStats assembled = assemble_streamed_stats(L, parts);
  auto bits = [](const StreamedStats& s) {  // every number's bytes, in order
    std::string out;
    auto put = [&](const truss::statistics::Stats& x, std::uint8_t ok) {
      out.append(reinterpret_cast<const char*>(&x.count), 8);
      for (double v : {x.mean, x.std, x.min, x.max}) out.append(reinterpret_cast<const char*>(&v), 8);
      for (double v : x.percentiles) out.append(reinterpret_cast<const char*>(&v), 8);
      out.push_back(static_cast<char>(ok));
    };
    for (std::size_t i = 0; i < s.f64.size(); ++i) put(s.f64[i], s.f64_resolved[i]);
    for (std::size_t f = 0; f < s.bays.size(); ++f)
      for (std::size_t b = 0; b < s.bays[f].size(); ++b) put(s.bays[f][b], s.bays_resolved[f][b]);
    return out;
  };
  CHECK(assembled.f64.size() == one.f64.size());
  CHECK(assembled.bays.size() == one.bays.size());
  CHECK(bits(assembled) == bits(one));
  CHECK(assembled.kept_values == one.kept_values);
  // A part missing (the last; one in the middle), or given twice: refused (parts: ranks 3, 1, 2).
  CHECK_THROWS_WITH(assemble_streamed_stats(L, {parts[1], parts[2]}), Catch::Contains("columns of"));
  CHECK_THROWS_WITH(assemble_streamed_stats(L, {parts[0], parts[1]}), Catch::Contains("a part from column"));
  CHECK_THROWS_WITH(assemble_streamed_stats(L, {parts[0], parts[1], parts[2], parts[0]}), Catch::Contains("a part from column"));
  CHECK_THROWS_AS(ChunkStats(L, ColumnRange{0, n_stats + 1}), std::invalid_argument);
}

// The read-back of statistics columns by any rank (read_back.hpp): the jobs found from the file's
// chunk index, the chunks read at those places and decoded by the codec, against HDF5's own filters
// reading the same dataset (H5Dread) and statistics::calc_stats; the jobs' shares and messages.
TEST_CASE("statistics read back by the ranks: the stored chunks at their places, as HDF5 reads them",
          "[campaign][store]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 40));
  const RecordLayout& L = ctx.record;
  const std::int64_t n = 40;
  Campaign c("truss_test_store_read_back.h5", L, StoreOptions{16, 1}, 2);
  c.add_round_of_distinct(n);
  StreamedStats s = c.close();
  // Every column unresolved: a job per statistics dataset.
  for (auto& r : s.f64_resolved) r = 0;
  for (auto& b : s.bays_resolved) std::fill(b.begin(), b.end(), 0);
  const StoreFile f(c.path);
  const std::vector<ReadBackJob> jobs = find_read_back(f.file, L, s, n);
  REQUIRE(jobs.size() == s.f64.size() + s.bays.size());
  std::vector<std::uint8_t> ok(static_cast<std::size_t>(n));
  const auto status = read_status(f.file, n);
  for (std::size_t i = 0; i < ok.size(); ++i) ok[i] = status[i] == 0;
  REQUIRE(std::count(ok.begin(), ok.end(), 1) > 10);
  ReadBackPlan plan{c.path, ok, jobs};
  const ReadBackPlan back = read_read_back_plan(to_bytes(plan));
  CHECK(to_bytes(back) == to_bytes(plan));
  StreamedStats applied = s;
  std::size_t checked = 0;
  for (const ReadBackJob& job : back.jobs) {
    REQUIRE(job.chunks.size() == 3);  // 40 rows in chunks of 16
    const std::vector<double> all = f.f64(job.path, n * job.width);  // HDF5's filters, not the codec
    const std::vector<ReadBackAnswer> a = read_read_back_answers(to_bytes(calc_read_back(back.path, job, back.ok)));
    REQUIRE(a.size() == job.columns.size());
    // In passes of 1 and 2 columns (each pass decodes every chunk again): the same answers.
    for (std::size_t group : {1, 2})
      CHECK(to_bytes(calc_read_back(back.path, job, back.ok, group)) == to_bytes(a));
    for (std::size_t k = 0; k < a.size(); ++k) {
      std::vector<double> col(static_cast<std::size_t>(n));
      for (std::int64_t i = 0; i < n; ++i) col[static_cast<std::size_t>(i)] = all[static_cast<std::size_t>(i * job.width + job.columns[k].column)];
      const auto want = truss::statistics::calc_stats(col, ok).percentiles;
      CHECK(std::memcmp(a[k].percentiles.data(), want.data(), sizeof(want)) == 0);
      ++checked;
    }
    apply_read_back(applied, a);
  }
  CHECK(checked == ChunkColumns(L).n_stats);
  CHECK(applied.read_back == static_cast<std::int64_t>(checked));
  CHECK(std::all_of(applied.f64_resolved.begin(), applied.f64_resolved.end(), [](auto r) { return r == 1; }));
  CHECK(applied.f64[0].mean == s.f64[0].mean);  // the streamed moments stand
  // Shares: every job once over the ranks, the largest first to the least loaded.
  for (int size : {1, 2, 3, 7}) {
    std::vector<int> times(jobs.size(), 0);
    for (int r = 0; r < size; ++r)
      for (std::size_t j : find_jobs_of(jobs, r, size)) ++times[j];
    CHECK(std::all_of(times.begin(), times.end(), [](int t) { return t == 1; }));
  }
  std::vector<ReadBackJob> sized(4);
  for (std::size_t j = 0; j < 4; ++j) sized[j].chunks.assign(1, {0, std::uint64_t{10} * (j + 1), 0});  // 10 20 30 40
  CHECK(find_jobs_of(sized, 0, 2) == std::vector<std::size_t>{3, 0});  // 40 + 10
  CHECK(find_jobs_of(sized, 1, 2) == std::vector<std::size_t>{2, 1});  // 30 + 20
  // A chunk that is not there: refused by name.
  ReadBackJob bad = jobs[0];
  bad.chunks[1].offset = std::uint64_t{1} << 40;
  CHECK_THROWS_WITH(calc_read_back(c.path, bad, ok), Catch::Contains("cannot be read"));
  CHECK_THROWS_AS(read_read_back_plan(to_bytes(plan).substr(1)), std::runtime_error);
}

TEST_CASE("result store: placing chunks while HDF5 writes its global heap", "[campaign][store]") {
  const CampaignContext ctx(test::small_campaign("latin_hypercube", 3000));
  const RecordLayout& L = ctx.record;
  const std::int64_t n = 3000;
  Campaign c("truss_test_store_heap.h5", L, StoreOptions{16, 1}, 2, {}, 64 << 10);
  c.add_round_of_distinct(n);
  c.close();
  const StoreFile f(c.path);
  check_file(f, L, n, 0, n);
}
