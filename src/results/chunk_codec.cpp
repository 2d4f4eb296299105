#include "results/chunk_codec.hpp"

#include <emmintrin.h>
#include <isa-l/igzip_lib.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <memory>
#include <utility>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

namespace truss::results {

namespace {

// Sixteen 8-byte elements at src: byte j of element i to dst[j * n + i] (i < 16, j < 8), in SSE2
// registers (every x86-64 has them). Each register holds two elements; interleaving its halves
// byte by byte gives eight 16-bit words, word j = byte j of both; an 8 x 8 transpose of those
// words (unpack by 16, 32, 64 bits) leaves register j = plane j. About 0.45 instructions a byte
// against 1.75 for the scalar 8 x 8 transpose in 64-bit words it replaces.
void transpose16(const unsigned char* src, std::size_t n, unsigned char* dst) {
  __m128i y[8], t[8], u[8];
  for (int i = 0; i < 8; ++i) {
    const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src + 16 * i));
    y[i] = _mm_unpacklo_epi8(x, _mm_srli_si128(x, 8));
  }
  for (int i = 0; i < 8; i += 2) {
    t[i] = _mm_unpacklo_epi16(y[i], y[i + 1]);
    t[i + 1] = _mm_unpackhi_epi16(y[i], y[i + 1]);
  }
  for (const int i : {0, 4}) {
    u[i] = _mm_unpacklo_epi32(t[i], t[i + 2]);
    u[i + 1] = _mm_unpackhi_epi32(t[i], t[i + 2]);
    u[i + 2] = _mm_unpacklo_epi32(t[i + 1], t[i + 3]);
    u[i + 3] = _mm_unpackhi_epi32(t[i + 1], t[i + 3]);
  }
  for (int k = 0; k < 4; ++k) {
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + (2 * k) * n), _mm_unpacklo_epi64(u[k], u[k + 4]));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst + (2 * k + 1) * n), _mm_unpackhi_epi64(u[k], u[k + 4]));
  }
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
  if (es == 8) {  // the common case: sixteen elements at a time, a byte transpose in registers
    const std::size_t n16 = n / 16 * 16;
    for (std::size_t i = 0; i < n16; i += 16) transpose16(src + i * 8, n, dst + i);
    for (std::size_t i = n16; i < n; ++i)
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

// The zlib header (RFC 1950) for `level`: CM 8 with a 32 kB window, FLEVEL as zlib maps the level
// (informative only: inflaters ignore it), FCHECK making the 16-bit header a multiple of 31.
void put_zlib_header(int level, std::string& out) {
  const unsigned flevel = level < 2 ? 0 : level < 6 ? 1 : level == 6 ? 2 : 3;
  unsigned h = (0x78u << 8) | (flevel << 6);
  h += 31 - h % 31;
  out.push_back(static_cast<char>(h >> 8));
  out.push_back(static_cast<char>(h & 0xff));
}

// bytes as stored blocks (RFC 1951, 3.2.4: BTYPE 00, at most 65,535 bytes each), the last one
// final when `final`. Each block starts on a byte boundary, and so does what follows it.
void put_stored_blocks(std::string_view bytes, bool final, std::string& out) {
  do {
    const std::size_t len = std::min<std::size_t>(bytes.size(), 65535);
    const bool last = final && len == bytes.size();
    const unsigned char head[5] = {static_cast<unsigned char>(last ? 1 : 0), static_cast<unsigned char>(len & 0xff),
                                   static_cast<unsigned char>(len >> 8), static_cast<unsigned char>(~len & 0xff),
                                   static_cast<unsigned char>((~len >> 8) & 0xff)};
    out.append(reinterpret_cast<const char*>(head), sizeof head);
    out.append(bytes.substr(0, len));
    bytes.remove_prefix(len);
  } while (!bytes.empty());
}

// What deflate would make of a sample of at most kSample bytes, estimated without running it (a
// deflate call is dearer than the whole estimate). Order-0 entropy H (s log2 s - sum c log2 c over
// the byte counts c, the size of a code that codes the bytes one by one) plus the Huffman tables,
// about 20 bytes and 0.3 a distinct byte (fitted to libdeflate level 1 on the planes of the Table-1
// campaign); or, if smaller, the same with the bytes that matches cover (count_matches) replaced by
// 2 bytes a match. It agrees with ISA-L's level 1 on whether a sample shrinks below 9/10 on 99.4 %
// of the planes of 10,000- and 100,000-run Table-1 campaigns; the others are planes deflated that
// ISA-L leaves at 0.90-0.96 of their size, never a plane stored that it would shrink.
constexpr std::size_t kSample = 1024;

const std::array<double, kSample + 1>& find_clogc() {  // c log2 c for c = 0 .. kSample
  static const std::array<double, kSample + 1> t = [] {
    std::array<double, kSample + 1> a{};
    for (std::size_t c = 1; c <= kSample; ++c) a[c] = static_cast<double>(c) * std::log2(static_cast<double>(c));
    return a;
  }();
  return t;
}

// Bytes of p[0, s) covered by greedy matches of 4 bytes or more, and their number: at each position
// the last one with the same hash of its 4 bytes, as the fastest deflate match finders (libdeflate's
// level 1, ISA-L's), which like this take no match of 3: a run of 4 equal bytes between others is
// 4 literals to them.
std::pair<std::size_t, std::size_t> count_matches(const unsigned char* p, std::size_t s) {
  constexpr std::uint16_t kNone = 0xffff;  // positions are < kSample
  std::array<std::uint16_t, 4096> last;
  last.fill(kNone);
  std::size_t covered = 0, matches = 0, i = 0;
  while (i + 4 <= s) {
    std::uint32_t v;
    std::memcpy(&v, p + i, 4);
    const std::uint32_t h = (v * 0x9E3779B1u) >> 20;
    const std::size_t at = last[h];
    last[h] = static_cast<std::uint16_t>(i);
    if (at == kNone || std::memcmp(p + at, p + i, 4) != 0) {
      ++i;
      continue;
    }
    std::size_t len = 4;
    while (i + len < s && p[at + len] == p[i + len]) ++len;
    covered += len;
    ++matches;
    i += len;
  }
  return {covered, matches};
}

// Whether deflate would leave p[0, s) at 9/10 of its size or more, by the estimate above; the
// matches are looked for only when the entropy alone does not already say it shrinks.
bool is_noise(const unsigned char* p, std::size_t s) {
  std::array<std::uint32_t, 4 * 256> h{};  // four histograms: no store waits on the one before
  std::size_t i = 0;
  for (; i + 4 <= s; i += 4)
    for (std::size_t k = 0; k < 4; ++k) ++h[256 * k + p[i + k]];
  for (; i < s; ++i) ++h[p[i]];
  const auto& clogc = find_clogc();
  double sum = 0.0;
  std::size_t distinct = 0;
  for (std::size_t b = 0; b < 256; ++b) {
    const std::uint32_t c = h[b] + h[256 + b] + h[512 + b] + h[768 + b];
    sum += clogc[c];
    distinct += c > 0;
  }
  const double entropy = (clogc[s] - sum) / 8.0, tables = 20.0 + 0.3 * static_cast<double>(distinct);
  const double line = 0.9 * static_cast<double>(s);
  if (entropy + tables < line) return false;
  const auto [covered, matches] = count_matches(p, s);
  const double rest = 1.0 - static_cast<double>(covered) / static_cast<double>(s);
  return entropy * rest + 2.0 * static_cast<double>(matches) + tables >= line;
}

// The leading byte planes of a shuffled chunk (es planes of `plane` bytes) that deflate hardly
// shrinks: those whose first kSample bytes are estimated not to deflate below 9/10 of their size.
// After the shuffle the planes of the low mantissa bytes come first, and of measured or dispersed
// values they are noise or nearly so: ISA-L's level 1 spends about 1 ns a byte on them to save under
// a tenth (3.4 us a Table-1 result), the estimate and the stored copy about 0.5 us.
// A pure function of the chunk's bytes: the file stays the same on any number of ranks.
std::size_t count_noise_planes(const unsigned char* shuffled, std::size_t plane, std::size_t es) {
  const std::size_t s = std::min(plane, kSample);
  std::size_t k = 0;
  while (k < es && s > 1 && is_noise(shuffled + k * plane, s)) ++k;
  return k;
}

// ISA-L's igzip level for a zlib level: 1 -> 1 (its fastest with dynamic Huffman codes), 2 -> 2,
// 3 to 9 -> 3 (its largest). On the Table-1 planes that compress, its level 1 takes 1.4 us a
// result, zlib's 8.7 and libdeflate's 4.2 (2.6 ns a byte over the constant sign-and-exponent plane
// that ends most chunks), for 189, 199 and 181 bytes (each library alone on those planes of a
// 10,000-run file; the whole codec: bench/bench_codec, docs/benchmarks.md). ISA-L's levels 2 and 3
// give the same sizes here; the strongest deflate (libdeflate's level 12, 110 times slower) would
// take 155 bytes, 1 % of the file (mostly stored noise planes).
int find_igzip_level(int level) { return std::min(level, 3); }

// `in` as one raw DEFLATE stream (its last block final) at the end of `out`, in at most `cap`
// bytes in all; false if it does not fit.
bool put_deflated(const unsigned char* in, std::size_t n, int level, std::size_t cap, std::string& out) {
  if (n > UINT32_MAX) throw std::length_error(fmt::format("chunk of {} bytes: ISA-L takes under 4 GiB", n));
  const int igzip = find_igzip_level(level);
  thread_local std::vector<unsigned char> level_buf;  // level 1 needs none (ISA-L's stateless)
  const std::size_t need = igzip == 2 ? ISAL_DEF_LVL2_DEFAULT : igzip == 3 ? ISAL_DEF_LVL3_DEFAULT : 0;
  if (level_buf.size() < need) level_buf.resize(need);
  const std::size_t at = out.size();
  if (at >= cap) return false;
  out.resize(cap);
  isal_zstream s;
  isal_deflate_stateless_init(&s);
  s.level = static_cast<std::uint32_t>(igzip);
  s.level_buf = need > 0 ? level_buf.data() : nullptr;
  s.level_buf_size = static_cast<std::uint32_t>(need);
  s.gzip_flag = IGZIP_DEFLATE;
  s.end_of_stream = 1;
  s.flush = NO_FLUSH;
  s.next_in = const_cast<unsigned char*>(in);  // not written: ISA-L's struct is not const-correct
  s.avail_in = static_cast<std::uint32_t>(n);
  s.next_out = reinterpret_cast<unsigned char*>(out.data() + at);
  s.avail_out = static_cast<std::uint32_t>(cap - at);
  const int r = isal_deflate_stateless(&s);
  if (r == STATELESS_OVERFLOW) return false;
  if (r != COMP_OK) throw std::runtime_error(fmt::format("ISA-L deflate (level {}): error {}", igzip, r));
  out.resize(at + s.total_out);
  return true;
}

// Shuffled, then the zlib stream: header, the noise planes as stored blocks, the rest as one
// ISA-L DEFLATE stream (its last block final), the Adler-32 of all of it (RFC 1950). Any
// inflater, HDF5's deflate filter among them, reads it like a single-call stream.
std::uint32_t encode_filtered(std::string_view raw, std::size_t elem_size, int level, std::string& out) {
  thread_local std::string shuffled;  // reused: a chunk's dataset is the same size each time
  shuffled.resize(raw.size());
  const auto* sh = reinterpret_cast<const unsigned char*>(shuffled.data());
  shuffle(reinterpret_cast<const unsigned char*>(raw.data()), raw.size(), elem_size,
          reinterpret_cast<unsigned char*>(shuffled.data()));
  if (level > 9) throw std::invalid_argument(fmt::format("deflate level {} (1 to 9)", level));
  const std::size_t es = std::max<std::size_t>(elem_size, 1), plane = raw.size() / es;
  const std::size_t stored = plane > 1 ? count_noise_planes(sh, plane, es) * plane : 0;
  // Larger than HDF5's output buffer: HDF5 skips the optional deflate filter, so do we.
  const std::size_t cap = hdf5_deflate_buffer(raw.size());
  const auto skip = [&] {
    out.assign(shuffled);
    return kDeflateSkipped;
  };
  out.clear();
  put_zlib_header(level, out);
  if (stored > 0) put_stored_blocks(std::string_view(shuffled).substr(0, stored), stored == raw.size(), out);
  if (out.size() + 4 > cap) return skip();
  if (stored < raw.size() && !put_deflated(sh + stored, raw.size() - stored, level, cap - 4, out)) return skip();
  const std::uint32_t adler = isal_adler32(1, sh, raw.size());
  for (const int shift : {24, 16, 8, 0}) out.push_back(static_cast<char>((adler >> shift) & 0xff));
  return 0;
}

}  // namespace

std::uint32_t encode_chunk(std::string_view raw, std::size_t elem_size, int level, std::string& out) {
  if (level <= 0) {
    out.assign(raw);
    return 0;
  }
  // A constant chunk (every element the same bytes: a quantity the scene never fills, NaN
  // throughout, or a count that does not vary) is encoded once per value, size and level and its
  // bytes reused: shuffle, ISA-L (0.06-0.3 ns a byte over runs of one byte) and Adler-32 cost
  // 0.2-0.5 ns a byte, the check 0.1 ns (and a chunk that is not constant fails it at once).
  struct Constant {
    int level;
    std::size_t elem_size, size;
    std::string element, encoded;
    std::uint32_t mask;
  };
  thread_local std::vector<Constant> constants;  // the few constant columns of a campaign
  const bool constant = raw.size() > elem_size && elem_size > 0 &&
                        std::memcmp(raw.data(), raw.data() + elem_size, raw.size() - elem_size) == 0;
  const std::string_view element = raw.substr(0, elem_size);
  if (constant)
    for (const Constant& c : constants)
      if (c.level == level && c.elem_size == elem_size && c.size == raw.size() && c.element == element) {
        out = c.encoded;
        return c.mask;
      }
  const std::uint32_t mask = encode_filtered(raw, elem_size, level, out);
  if (constant) {
    if (constants.size() >= 64) constants.clear();
    constants.push_back({level, elem_size, raw.size(), std::string(element), out, mask});
  }
  return mask;
}

}  // namespace truss::results
