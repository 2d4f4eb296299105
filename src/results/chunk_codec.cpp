#include "results/chunk_codec.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::results {

namespace {

// Eight 8-byte elements at src: byte j of element i to dst[j * n + i] (i, j < 8). Row i of the
// matrix is element i, loaded as one word (byte j in bits 8 j: little-endian); three rounds swap
// its 4 x 4, 2 x 2 and 1 x 1 blocks across the diagonal (Hacker's Delight, 7-3, by bytes), after
// which word j is plane j. Halves encode_chunk's own time against the byte-by-byte loop.
void transpose8(const unsigned char* src, std::size_t n, unsigned char* dst) {
  static_assert(std::endian::native == std::endian::little);
  std::uint64_t r[8];
  std::memcpy(r, src, sizeof r);
  for (std::size_t i = 0; i < 4; ++i) {
    const std::uint64_t t = ((r[i] >> 32) ^ r[i + 4]) & 0x00000000FFFFFFFFull;
    r[i] ^= t << 32;
    r[i + 4] ^= t;
  }
  for (const std::size_t i : {0, 1, 4, 5}) {
    const std::uint64_t t = ((r[i] >> 16) ^ r[i + 2]) & 0x0000FFFF0000FFFFull;
    r[i] ^= t << 16;
    r[i + 2] ^= t;
  }
  for (std::size_t i = 0; i < 8; i += 2) {
    const std::uint64_t t = ((r[i] >> 8) ^ r[i + 1]) & 0x00FF00FF00FF00FFull;
    r[i] ^= t << 8;
    r[i + 1] ^= t;
  }
  for (std::size_t j = 0; j < 8; ++j) std::memcpy(dst + j * n, &r[j], 8);
}

// H5Zshuffle.c: byte j of element i goes to j * n + i (n = nbytes / elem_size); a trailing
// partial element (never here: chunks hold whole elements) stays in place. Sizes 1 and a single
// element are left as they are.
void shuffle(const unsigned char* src, std::size_t nbytes, std::size_t es, unsigned char* dst) {
  const std::size_t n = nbytes / es;
  if (es <= 1 || n <= 1) {
    std::copy_n(src, nbytes, dst);
    return;
  }
  if (es == 8) {  // the common case: eight elements at a time, an 8 x 8 byte transpose in registers
    const std::size_t n8 = n / 8 * 8;
    for (std::size_t i = 0; i < n8; i += 8) transpose8(src + i * 8, n, dst + i);
    for (std::size_t i = n8; i < n; ++i)
      for (std::size_t j = 0; j < 8; ++j) dst[j * n + i] = src[i * 8 + j];
  } else {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < es; ++j) dst[j * n + i] = src[i * es + j];
  }
  std::copy(src + n * es, src + nbytes, dst + n * es);
}

// H5Z_DEFLATE_SIZE_ADJUST of HDF5 1.10: the output buffer H5Z_filter_deflate gives compress2.
std::size_t hdf5_deflate_buffer(std::size_t nbytes) {
  return static_cast<std::size_t>(std::ceil(static_cast<double>(nbytes) * static_cast<double>(1.001f)) + 12.0);
}

}  // namespace

std::uint32_t encode_chunk(std::string_view raw, std::size_t elem_size, int level, std::string& out) {
  if (level <= 0) {
    out.assign(raw);
    return 0;
  }
  thread_local std::string shuffled;  // reused: a chunk's dataset is the same size each time
  shuffled.resize(raw.size());
  shuffle(reinterpret_cast<const unsigned char*>(raw.data()), raw.size(), elem_size,
          reinterpret_cast<unsigned char*>(shuffled.data()));
  // libdeflate's zlib-format stream (RFC 1950), which HDF5's deflate filter inflates like its own:
  // twice zlib's compress2 speed at level 1 on these shuffled columns, the same ratio
  // (docs/benchmarks.md). One compressor per level (allocating one costs more than a chunk).
  struct Free {
    void operator()(libdeflate_compressor* c) const { libdeflate_free_compressor(c); }
  };
  static std::array<std::unique_ptr<libdeflate_compressor, Free>, 10> compressors;
  if (level > 9) throw std::invalid_argument(fmt::format("deflate level {} (1 to 9)", level));
  auto& c = compressors[static_cast<std::size_t>(level)];
  if (!c) c.reset(libdeflate_alloc_compressor(level));
  if (!c) throw std::runtime_error(fmt::format("libdeflate: no compressor for level {}", level));
  const std::size_t cap = hdf5_deflate_buffer(raw.size());
  out.resize(cap);
  const std::size_t z = libdeflate_zlib_compress(c.get(), shuffled.data(), shuffled.size(), out.data(), cap);
  if (z == 0) {  // larger than HDF5's output buffer: HDF5 skips the optional deflate filter, so do we
    out.assign(shuffled);
    return kDeflateSkipped;
  }
  out.resize(z);
  return 0;
}

}  // namespace truss::results
