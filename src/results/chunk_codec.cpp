// The chunk codec: the filters' definitions are in chunk_codec.hpp.
#include "results/chunk_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "util/isal.hpp"

namespace truss::results {

namespace {

// H5Zshuffle.c: byte j of element i goes to j * n + i (n = nbytes / elem_size); a trailing
// partial element (never here: chunks hold whole elements) stays in place. Sizes 1 and a single
// element are left as they are.
void shuffle(const unsigned char* src, std::size_t nbytes, std::size_t es, unsigned char* dst) {
  const std::size_t n = nbytes / es;
  if (es <= 1 || n <= 1) {
    std::copy_n(src, nbytes, dst);
    return;
  }
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < es; ++j) dst[j * n + i] = src[i * es + j];
  std::copy(src + n * es, src + nbytes, dst + n * es);
}

// shuffle's inverse: byte j * n + i goes back to byte j of element i. Elements of 8 bytes (every
// float64 and int64 column) with the size known to the compiler: each element then gathers its 8
// bytes from the 8 planes in one unrolled pass.
template <std::size_t Es>
void unshuffle_fixed(const unsigned char* src, std::size_t n, unsigned char* dst) {
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < Es; ++j) dst[i * Es + j] = src[j * n + i];
}

void unshuffle(const unsigned char* src, std::size_t nbytes, std::size_t es, unsigned char* dst) {
  const std::size_t n = nbytes / es;
  if (es <= 1 || n <= 1) {
    std::copy_n(src, nbytes, dst);
    return;
  }
  if (es == 8) {
    unshuffle_fixed<8>(src, n, dst);
  } else {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < es; ++j) dst[i * es + j] = src[j * n + i];
  }
  std::copy(src + n * es, src + nbytes, dst + n * es);
}

// H5Z_DEFLATE_SIZE_ADJUST of HDF5 1.10: the output buffer H5Z_filter_deflate gives compress2.
std::size_t hdf5_deflate_buffer(std::size_t nbytes) {
  return static_cast<std::size_t>(std::ceil(static_cast<double>(nbytes) * static_cast<double>(1.001f)) + 12.0);
}

// The zlib header (RFC 1950) for `level`: CM 8 with a 32 kB window, FLEVEL as zlib maps the level
// (informative only: inflaters ignore it), FCHECK making the 16-bit header a multiple of 31.
void put_zlib_header(int level, std::string& out) {
  const unsigned flevel = level < 2 ? 0 : level < 6 ? 1 : level == 6 ? 2 : 3;
  unsigned h = (0x78u << 8) | (flevel << 6);
  h += 31 - h % 31;
  out.push_back(static_cast<char>(h >> 8));
  out.push_back(static_cast<char>(h & 0xff));
}

// ISA-L's igzip level for a zlib level: 1 -> 1 (its fastest with dynamic Huffman codes), 2 -> 2,
// 3 to 9 -> 3 (its largest).
int find_igzip_level(int level) { return std::min(level, 3); }

}  // namespace

// `in` as one raw DEFLATE stream (its last block final) at the end of `out`, in at most `cap`
// bytes in all; false if it does not fit.
bool ChunkCodec::put_deflated(const unsigned char* in, std::size_t n, int level, std::size_t cap, std::string& out) {
  const std::size_t at = out.size();
  if (at >= cap) return false;
  out.resize(cap);
  const std::optional<std::size_t> written =
      deflater_.deflate(in, n, find_igzip_level(level), reinterpret_cast<unsigned char*>(out.data() + at), cap - at);
  if (!written) return false;
  out.resize(at + *written);
  return true;
}

// Shuffled, then the zlib stream: header, the shuffled bytes as one ISA-L DEFLATE stream (its last
// block final), the Adler-32 of the shuffled bytes (RFC 1950). Any inflater, HDF5's deflate filter
// among them, reads it.
std::uint32_t ChunkCodec::encode_filtered(std::string_view raw, std::size_t elem_size, int level, std::string& out) {
  if (level > 9) throw std::invalid_argument(fmt::format("deflate level {} (1 to 9)", level));
  shuffled_.resize(raw.size());
  const auto* sh = reinterpret_cast<const unsigned char*>(shuffled_.data());
  shuffle(reinterpret_cast<const unsigned char*>(raw.data()), raw.size(), std::max<std::size_t>(elem_size, 1),
          reinterpret_cast<unsigned char*>(shuffled_.data()));
  // Larger than HDF5's output buffer: HDF5 skips the optional deflate filter, so do we.
  const std::size_t cap = hdf5_deflate_buffer(raw.size());
  out.clear();
  put_zlib_header(level, out);
  if (!put_deflated(sh, raw.size(), level, cap - 4, out)) {
    out.assign(shuffled_);
    return kDeflateSkipped;
  }
  const std::uint32_t adler = util::calc_adler32(sh, raw.size());
  for (const int shift : {24, 16, 8, 0}) out.push_back(static_cast<char>((adler >> shift) & 0xff));
  return 0;
}

std::uint32_t ChunkCodec::encode(std::string_view raw, std::size_t elem_size, int level, std::string& out) {
  if (level <= 0) {
    out.assign(raw);
    return 0;
  }
  // A constant chunk (a quantity the scene never fills, NaN throughout, or a count that does not
  // vary) is encoded once per value, size and level and its bytes reused; a chunk that is not
  // constant fails the check at its first differing element.
  const bool constant = raw.size() > elem_size && elem_size > 0 &&
                        std::memcmp(raw.data(), raw.data() + elem_size, raw.size() - elem_size) == 0;
  const std::string_view element = raw.substr(0, elem_size);
  if (constant)
    for (const Constant& c : constants_)
      if (c.level == level && c.elem_size == elem_size && c.size == raw.size() && c.element == element) {
        out = c.encoded;
        return c.mask;
      }
  const std::uint32_t mask = encode_filtered(raw, elem_size, level, out);
  if (constant) {
    if (constants_.size() >= kMaxConstants) constants_.clear();
    constants_.push_back({level, elem_size, raw.size(), std::string(element), out, mask});
  }
  return mask;
}

void ChunkCodec::decode(std::string_view stored, std::uint32_t mask, bool filtered, std::size_t elem_size,
                        std::size_t raw_size, std::string& raw) {
  raw.resize(raw_size);
  auto* out = reinterpret_cast<unsigned char*>(raw.data());
  const auto* in = reinterpret_cast<const unsigned char*>(stored.data());
  if (!filtered || (mask & kShuffleSkipped && mask & kDeflateSkipped)) {
    if (stored.size() != raw_size)
      throw std::runtime_error(fmt::format("a stored chunk of {} bytes for {} bytes", stored.size(), raw_size));
    std::copy_n(in, raw_size, out);
    return;
  }
  if (!(mask & kDeflateSkipped)) {
    shuffled_.resize(raw_size);
    if (!util::inflate_zlib(in, stored.size(), reinterpret_cast<unsigned char*>(shuffled_.data()), raw_size))
      throw std::runtime_error(fmt::format("a stored chunk of {} bytes is not a zlib stream of {} bytes",
                                           stored.size(), raw_size));
    in = reinterpret_cast<const unsigned char*>(shuffled_.data());
  } else if (stored.size() != raw_size) {
    throw std::runtime_error(fmt::format("a shuffled chunk of {} bytes for {} bytes", stored.size(), raw_size));
  }
  if (mask & kShuffleSkipped) std::copy_n(in, raw_size, out);
  else unshuffle(in, raw_size, std::max<std::size_t>(elem_size, 1), out);
}

}  // namespace truss::results
