// Does every stored chunk of a results file re-encode, in this process, to the bytes a campaign
// stored? The promise checked: results::ChunkCodec's output is a pure function of the chunk's
// values (chunk_codec.hpp), so a chunk's bytes do not depend on which rank, which session or which
// history of calls encoded it. When two files of equal values differ in a chunk's compressed bytes
// (a resume check), this names the file whose chunk is not what the codec writes now.
//
// For each chunked dataset whose pipeline is shuffle + deflate (every per-run dataset but strings),
// each chunk is read as stored (H5Dread_chunk), inflated with zlib and unshuffled to its raw bytes,
// then encoded REPEATS times by one ChunkCodec, as a writer does, and compared with the stored bytes.
// Prints a line per chunk that differs (or whose encodings disagree with each other) and a summary;
// exit 0 when every chunk re-encodes to its stored bytes, 1 otherwise, 2 on bad input.
// Usage: truss_reencode_chunks FILE.h5 [REPEATS]   (REPEATS: 3)
#include <hdf5.h>
#include <zlib.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "results/chunk_codec.hpp"

namespace {

using truss::results::ChunkCodec;

struct Tally {
  long chunks = 0, differ = 0, disagree = 0;
};

// The pipeline of a chunked dataset: the deflate level (0 when there is no deflate filter) and
// whether the shuffle filter comes first; false when it is another pipeline (not checked).
bool find_pipeline(hid_t dcpl, int& level, bool& shuffle) {
  level = 0;
  shuffle = false;
  const int n = H5Pget_nfilters(dcpl);
  for (int i = 0; i < n; ++i) {
    unsigned flags = 0, cd[8] = {};
    size_t n_cd = 8;
    char name[64];
    const H5Z_filter_t id = H5Pget_filter2(dcpl, static_cast<unsigned>(i), &flags, &n_cd, cd, sizeof name, name, nullptr);
    if (id == H5Z_FILTER_SHUFFLE && i == 0) shuffle = true;
    else if (id == H5Z_FILTER_DEFLATE && n_cd >= 1) level = static_cast<int>(cd[0]);
    else return false;
  }
  return level > 0;
}

// The raw chunk of `stored` (mask: the filters skipped): inflated, then unshuffled.
bool calc_raw(const std::string& stored, unsigned mask, std::size_t chunk_bytes, std::size_t elem, bool shuffle,
              std::string& raw) {
  std::string sh(chunk_bytes, '\0');
  if (mask & truss::results::kDeflateSkipped) {
    sh = stored;
  } else {
    uLongf len = static_cast<uLongf>(chunk_bytes);
    if (uncompress(reinterpret_cast<Bytef*>(sh.data()), &len, reinterpret_cast<const Bytef*>(stored.data()),
                   static_cast<uLong>(stored.size())) != Z_OK || len != chunk_bytes)
      return false;
  }
  if (!shuffle || (mask & truss::results::kShuffleSkipped) || elem <= 1) {
    raw = sh;
    return sh.size() == chunk_bytes;
  }
  const std::size_t n = chunk_bytes / elem;
  raw.assign(chunk_bytes, '\0');
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < elem; ++j) raw[i * elem + j] = sh[j * n + i];
  return true;
}

void check_dataset(hid_t ds, const std::string& path, int repeats, ChunkCodec& codec, Tally& t) {
  hid_t dcpl = H5Dget_create_plist(ds), type = H5Dget_type(ds), space = H5Dget_space(ds);
  int level = 0;
  bool shuffle = false;
  hsize_t cdims[4] = {1, 1, 1, 1};
  const int rank = H5Sget_simple_extent_ndims(space);
  if (H5Pget_layout(dcpl) == H5D_CHUNKED && H5Tget_class(type) != H5T_STRING && rank > 0 && rank <= 4 &&
      find_pipeline(dcpl, level, shuffle)) {
    H5Pget_chunk(dcpl, rank, cdims);
    const std::size_t elem = H5Tget_size(type);
    std::size_t chunk_bytes = elem;
    for (int d = 0; d < rank; ++d) chunk_bytes *= cdims[d];
    hsize_t n_chunks = 0;
    H5Dget_num_chunks(ds, space, &n_chunks);  // HDF5 1.10.8 refuses H5S_ALL here
    std::string stored, raw, fresh, again;
    for (hsize_t k = 0; k < n_chunks; ++k) {
      hsize_t offset[4] = {};
      unsigned mask = 0;
      haddr_t addr = 0;
      hsize_t size = 0;
      H5Dget_chunk_info(ds, space, k, offset, &mask, &addr, &size);
      stored.assign(size, '\0');
      uint32_t read_mask = 0;
      ++t.chunks;
      if (H5Dread_chunk(ds, H5P_DEFAULT, offset, &read_mask, stored.data()) < 0 ||
          !calc_raw(stored, read_mask, chunk_bytes, elem, shuffle, raw)) {
        std::printf("%s chunk at %llu: does not inflate to %zu bytes\n", path.c_str(),
                    static_cast<unsigned long long>(offset[0]), chunk_bytes);
        ++t.differ;
        continue;
      }
      const unsigned got_mask = codec.encode(raw, elem, level, fresh);
      bool agree = true;
      for (int r = 1; r < repeats; ++r) agree = codec.encode(raw, elem, level, again) == got_mask && again == fresh && agree;
      t.disagree += !agree;
      if (got_mask != read_mask || fresh != stored || !agree) {
        ++t.differ;
        std::printf("%s chunk at %llu: stored mask %u, %zu bytes; encoded now mask %u, %zu bytes, %s; %d encodings %s\n",
                    path.c_str(), static_cast<unsigned long long>(offset[0]), read_mask, stored.size(), got_mask,
                    fresh.size(), fresh == stored ? "equal" : "different bytes", repeats, agree ? "agree" : "DISAGREE");
      }
    }
  }
  H5Sclose(space);
  H5Tclose(type);
  H5Pclose(dcpl);
}

void visit(hid_t group, const std::string& path, int repeats, ChunkCodec& codec, Tally& t) {
  H5G_info_t info;
  H5Gget_info(group, &info);
  for (hsize_t k = 0; k < info.nlinks; ++k) {
    char name[256];
    H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT);
    H5O_info_t oi;
    H5Oget_info_by_name(group, name, &oi, H5P_DEFAULT);
    const std::string child = path + "/" + name;
    if (oi.type == H5O_TYPE_GROUP) {
      hid_t g = H5Gopen2(group, name, H5P_DEFAULT);
      visit(g, child, repeats, codec, t);
      H5Gclose(g);
    } else if (oi.type == H5O_TYPE_DATASET) {
      hid_t ds = H5Dopen2(group, name, H5P_DEFAULT);
      check_dataset(ds, child, repeats, codec, t);
      H5Dclose(ds);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 3;
  if (argc < 2 || argc > 3 || repeats < 1) {
    std::fprintf(stderr, "usage: truss_reencode_chunks FILE.h5 [REPEATS >= 1]\n");
    return 2;
  }
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const hid_t file = H5Fopen(argv[1], H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) {
    std::fprintf(stderr, "error: %s: not an HDF5 file that can be opened\n", argv[1]);
    return 2;
  }
  ChunkCodec codec;
  Tally t;
  hid_t root = H5Gopen2(file, "/", H5P_DEFAULT);
  visit(root, "", repeats, codec, t);
  H5Gclose(root);
  H5Fclose(file);
  std::printf("%ld of %ld deflated chunks re-encode to their stored bytes; %ld with encodings that disagree\n",
              t.chunks - t.differ, t.chunks, t.disagree);
  return t.differ == 0 && t.chunks > 0 ? 0 : 1;
}
