// One HDF5 chunk as HDF5's filter pipeline stores it, computed outside HDF5: the byte shuffle
// filter (H5Z_FILTER_SHUFFLE, as H5Zshuffle.c) then the deflate filter (H5Z_FILTER_DEFLATE: a
// zlib-format stream at the dataset's level, here from Intel's ISA-L, and HDF5 1.10's rule of
// H5Zdeflate.c for a chunk that does not shrink). The results file's per-run datasets are written
// chunk by chunk with H5Dwrite_chunk from these bytes: this codec encodes Table-1 chunks about 20
// times as fast as zlib's level 1, the call inside HDF5's own deflate filter, to the same size
// (bench/bench_codec, docs/benchmarks.md), and HDF5 1.10 does not let a program replace that
// predefined filter (H5Zregister refuses its id). The leading byte planes that deflate would shrink by under a
// tenth (the low mantissa bytes of dispersed and computed values, random or nearly: told by their
// byte entropy and repeats, without deflating them) go into the zlib stream as DEFLATE's stored
// blocks, the rest is compressed, and a constant chunk is compressed once per value. Readers
// (h5py, pandas, xarray) see an ordinary shuffled, deflated dataset.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace truss::results {

// Filter mask bits of H5Dwrite_chunk / H5Dread_chunk: bit i set = filter i of the pipeline skipped.
inline constexpr std::uint32_t kShuffleSkipped = 1u << 0;
inline constexpr std::uint32_t kDeflateSkipped = 1u << 1;

// Encodes `raw` (a whole chunk, elements of elem_size bytes) for a dataset whose pipeline is
// shuffle + deflate(level) (level 1..9) or no filter at all (level 0: the raw bytes, mask 0).
// Returns the filter mask. As in HDF5, deflate is optional: a chunk whose compressed form would
// exceed HDF5's output buffer (nbytes * 1.001 + 12, H5Z_DEFLATE_SIZE_ADJUST) is stored shuffled
// only, with kDeflateSkipped.
std::uint32_t encode_chunk(std::string_view raw, std::size_t elem_size, int level, std::string& out);

}  // namespace truss::results
