// One HDF5 chunk as HDF5's filter pipeline stores it, computed outside HDF5: the byte shuffle
// filter (H5Z_FILTER_SHUFFLE, as H5Zshuffle.c) then the deflate filter (H5Z_FILTER_DEFLATE: a
// zlib-format stream, RFC 1950, whose DEFLATE data (RFC 1951) comes from Intel's ISA-L, with HDF5
// 1.10's rule of H5Zdeflate.c for a chunk that does not shrink). The results file's per-run datasets
// are written chunk by chunk with H5Dwrite_chunk from these bytes; HDF5 1.10 does not let a program
// replace its predefined deflate filter (H5Zregister refuses its id), and ISA-L deflates these chunks
// several times as fast as zlib (bench/bench_codec, docs/benchmarks.md). A constant chunk is
// compressed once per value. Readers (h5py, pandas, xarray) see an ordinary shuffled, deflated
// dataset.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "util/isal.hpp"

namespace truss::results {

// Filter mask bits of H5Dwrite_chunk / H5Dread_chunk: bit i set = filter i of the pipeline skipped.
inline constexpr std::uint32_t kShuffleSkipped = 1u << 0;
inline constexpr std::uint32_t kDeflateSkipped = 1u << 1;

// The encoder of one results file (owned by its store): its work space and its memo of constant
// chunks are members, reused from chunk to chunk. Its output is a pure function of each call's
// arguments: the file stays the same on any number of ranks.
class ChunkCodec {
 public:
  // Encodes `raw` (a whole chunk, elements of elem_size bytes) for a dataset whose pipeline is
  // shuffle + deflate(level) (level 1..9) or no filter at all (level 0: the raw bytes, mask 0).
  // Returns the filter mask. As in HDF5, deflate is optional: a chunk whose compressed form would
  // exceed HDF5's output buffer (nbytes * 1.001 + 12, H5Z_DEFLATE_SIZE_ADJUST) is stored shuffled
  // only, with kDeflateSkipped.
  std::uint32_t encode(std::string_view raw, std::size_t elem_size, int level, std::string& out);
  // The inverse, for reading a finished file back: the raw_size bytes of a chunk stored as `stored`
  // with filter mask `mask` by a dataset whose pipeline is shuffle + deflate (filtered) or empty,
  // into raw. Any writer's chunk of such a dataset decodes (ISA-L inflates every zlib stream).
  // Throws std::runtime_error when `stored` is not such a chunk.
  void decode(std::string_view stored, std::uint32_t mask, bool filtered, std::size_t elem_size, std::size_t raw_size,
              std::string& raw);

 private:
  std::uint32_t encode_filtered(std::string_view raw, std::size_t elem_size, int level, std::string& out);
  bool put_deflated(const unsigned char* in, std::size_t n, int level, std::size_t cap, std::string& out);

  struct Constant {  // a constant chunk (every element the same bytes) and its encoding
    int level;
    std::size_t elem_size, size;
    std::string element, encoded;
    std::uint32_t mask;
  };
  std::string shuffled_;                   // the chunk after the shuffle filter (encode, decode)
  util::Deflater deflater_;                // ISA-L's igzip with its work space
  std::vector<Constant> constants_;        // at most kMaxConstants, the few constant columns
  static constexpr std::size_t kMaxConstants = 64;
};

}  // namespace truss::results
