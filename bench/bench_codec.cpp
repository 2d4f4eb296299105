// Benchmark (not a test): the results file's chunk codec against zlib, on the chunks of a real
// campaign file. For every 8-byte dataset of /runs (bays/ and inputs/ included), chunk by chunk
// as the file stores them (its own chunk rows), the values are read back and encoded
//   codec: results::ChunkCodec at level 1 (shuffle, ISA-L, Adler-32), what rank 0 runs;
//   zlib:  compress2 at level 1 of the same chunk shuffled (the call inside HDF5's own deflate
//          filter; its shuffle not timed).
// Chunks whose elements are all equal are skipped (the codec encodes those once per value).
// And the way back, as the end of a campaign reads columns (read_columns.cpp), each codec stream:
//   decode: results::ChunkCodec::decode (ISA-L's inflate, then the unshuffle);
//   zlib:   uncompress (HDF5's deflate filter reading it) then the same unshuffle as H5Zshuffle.c.
// Thread CPU time, medians of REPEATS passes, per run of the file.
// Usage: bench_codec FILE.h5 [REPEATS]
#include <hdf5.h>
#include <time.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "results/chunk_codec.hpp"

namespace {

double cpu_s() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Every chunk of every 8-byte numeric dataset under `group`, as raw bytes (the last one padded
// with zeros, as rank 0 writes it).
void collect(hid_t file, const std::string& group, std::vector<std::string>& chunks, long long& n_runs) {
  hid_t g = H5Gopen2(file, group.c_str(), H5P_DEFAULT);
  H5G_info_t info;
  H5Gget_info(g, &info);
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    char name[256];
    H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT);
    H5O_info_t oi;
    H5Oget_info_by_name(g, name, &oi, H5P_DEFAULT);
    if (oi.type == H5O_TYPE_GROUP) {
      collect(file, group + "/" + name, chunks, n_runs);
      continue;
    }
    hid_t ds = H5Dopen2(g, name, H5P_DEFAULT), type = H5Dget_type(ds), space = H5Dget_space(ds);
    hid_t dcpl = H5Dget_create_plist(ds);
    const bool numeric = H5Tget_class(type) != H5T_STRING && H5Tget_size(type) == 8;
    hsize_t dims[2] = {0, 1}, cdims[2] = {0, 1};
    const int rank = H5Sget_simple_extent_dims(space, dims, nullptr);
    if (numeric && H5Pget_layout(dcpl) == H5D_CHUNKED) {
      H5Pget_chunk(dcpl, 2, cdims);
      n_runs = static_cast<long long>(dims[0]);
      const hid_t mem = H5Tget_class(type) == H5T_FLOAT ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
      std::vector<char> all(dims[0] * (rank == 2 ? dims[1] : 1) * 8);
      H5Dread(ds, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, all.data());
      const std::size_t row = (rank == 2 ? dims[1] : 1) * 8;
      for (hsize_t r0 = 0; r0 < dims[0]; r0 += cdims[0]) {
        std::string c(cdims[0] * row, '\0');
        std::memcpy(c.data(), all.data() + r0 * row, std::min<hsize_t>(cdims[0], dims[0] - r0) * row);
        if (std::memcmp(c.data(), c.data() + 8, c.size() - 8) != 0) chunks.push_back(std::move(c));
      }
    }
    H5Pclose(dcpl);
    H5Sclose(space);
    H5Tclose(type);
    H5Dclose(ds);
  }
  H5Gclose(g);
}

std::string shuffled(const std::string& raw) {
  const std::size_t n = raw.size() / 8;
  std::string s(raw.size(), '\0');
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < 8; ++j) s[j * n + i] = raw[8 * i + j];
  return s;
}

void unshuffle(const std::string& s, std::string& raw) {
  const std::size_t n = s.size() / 8;
  raw.resize(s.size());
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < 8; ++j) raw[8 * i + j] = s[j * n + i];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_codec FILE.h5 [REPEATS]\n");
    return 2;
  }
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 5;
  hid_t file = H5Fopen(argv[1], H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return 2;
  std::vector<std::string> chunks;
  long long n_runs = 0;
  collect(file, "/runs", chunks, n_runs);
  H5Fclose(file);
  std::vector<std::string> sh;
  std::size_t raw_bytes = 0;
  for (const std::string& c : chunks) {
    sh.push_back(shuffled(c));
    raw_bytes += c.size();
  }
  std::vector<double> t_codec, t_zlib;
  std::size_t z_codec = 0, z_zlib = 0;
  truss::results::ChunkCodec codec;
  std::string out;
  std::vector<Bytef> zout;
  for (int r = 0; r < repeats; ++r) {
    z_codec = z_zlib = 0;
    double t0 = cpu_s();
    for (const std::string& c : chunks) {
      codec.encode(c, 8, 1, out);
      z_codec += out.size();
    }
    double t1 = cpu_s();
    for (const std::string& s : sh) {
      zout.resize(compressBound(s.size()));
      uLongf len = zout.size();
      if (compress2(zout.data(), &len, reinterpret_cast<const Bytef*>(s.data()), s.size(), 1) != Z_OK) return 1;
      z_zlib += len;
    }
    const double t2 = cpu_s();
    t_codec.push_back(t1 - t0);
    t_zlib.push_back(t2 - t1);
  }
  // The way back: every chunk's codec stream, decoded by each reader (checked against the chunk).
  std::vector<std::string> streams;
  std::vector<std::uint32_t> masks;
  for (const std::string& c : chunks) {
    masks.push_back(codec.encode(c, 8, 1, out));
    streams.push_back(out);
  }
  std::vector<double> t_decode, t_inflate;
  std::string back, inflated;
  truss::results::ChunkCodec decoder;
  for (int r = 0; r < repeats; ++r) {
    const double t0 = cpu_s();
    for (std::size_t k = 0; k < streams.size(); ++k) {
      decoder.decode(streams[k], masks[k], true, 8, chunks[k].size(), back);
      if (r == 0 && back != chunks[k]) return 1;
    }
    const double t1 = cpu_s();
    for (std::size_t k = 0; k < streams.size(); ++k) {
      if (masks[k] != 0) {  // stored shuffled only (the codec's one other form)
        unshuffle(streams[k], back);
        continue;
      }
      inflated.resize(chunks[k].size());
      uLongf len = inflated.size();
      if (uncompress(reinterpret_cast<Bytef*>(inflated.data()), &len, reinterpret_cast<const Bytef*>(streams[k].data()),
                     streams[k].size()) != Z_OK)
        return 1;
      unshuffle(inflated, back);
      if (r == 0 && back != chunks[k]) return 1;
    }
    const double t2 = cpu_s();
    t_decode.push_back(t1 - t0);
    t_inflate.push_back(t2 - t1);
  }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  const double n = static_cast<double>(n_runs);
  std::printf("runs=%lld chunks=%zu raw_bytes_per_run=%.0f\n", n_runs, chunks.size(), raw_bytes / n);
  std::printf("codec (level 1): %.2f us a run, %.0f bytes a run\n", 1e6 * median(t_codec) / n, z_codec / n);
  std::printf("zlib  (level 1): %.2f us a run, %.0f bytes a run\n", 1e6 * median(t_zlib) / n, z_zlib / n);
  std::printf("speed ratio zlib/codec: %.1f\n", median(t_zlib) / median(t_codec));
  std::printf("read back: decode %.2f us a run, zlib + unshuffle %.2f us a run, ratio %.2f\n",
              1e6 * median(t_decode) / n, 1e6 * median(t_inflate) / n, median(t_inflate) / median(t_decode));
  return 0;
}
