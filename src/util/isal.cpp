#include "util/isal.hpp"

#include <isa-l/crc.h>
#include <isa-l/igzip_lib.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::util {

namespace {

// VZEROUPPER after an ISA-L kernel (isal.hpp): an AVX instruction, executed only where the CPU has
// AVX (looked up once). A no-op outside x86-64.
#if defined(__x86_64__)
void clear_upper_vector_state() {
  static const bool has_avx = __builtin_cpu_supports("avx");
  if (has_avx) asm volatile("vzeroupper" ::: "memory");
}
#else
void clear_upper_vector_state() {}
#endif

}  // namespace

// ISA-L's CRC-32 (reflected, as zlib's crc32: the same values; folded with carry-less
// multiplication where the CPU has it; docs/benchmarks.md). Every record is checksummed twice
// (sealed by its rank, checked by rank 0).
std::uint32_t calc_crc32(std::string_view bytes, std::uint32_t crc) {
  const std::uint32_t out = crc32_gzip_refl(crc, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
  clear_upper_vector_state();
  return out;
}

std::uint32_t calc_adler32(const unsigned char* bytes, std::size_t n, std::uint32_t adler) {
  const std::uint32_t out = isal_adler32(adler, bytes, n);
  clear_upper_vector_state();
  return out;
}

std::optional<std::size_t> Deflater::deflate(const unsigned char* in, std::size_t n, int level, unsigned char* out,
                                             std::size_t cap) {
  if (n > UINT32_MAX) throw std::length_error(fmt::format("chunk of {} bytes: ISA-L takes under 4 GiB", n));
  if (level < 1 || level > 3) throw std::invalid_argument(fmt::format("igzip level {} (1 to 3)", level));
  const std::size_t need = level == 2 ? ISAL_DEF_LVL2_DEFAULT : level == 3 ? ISAL_DEF_LVL3_DEFAULT : 0;
  if (level_buf_.size() < need) level_buf_.resize(need);  // level 1 needs none
  // Zeroed, not only initialised: ISA-L's stateless level 1 works in the stream's own buffer and
  // reads parts of it it never wrote (valgrind), so a stream on a dirty stack gave a chunk of the
  // same values other bytes on other ranks (82 kB zeroed a call, against a chunk's deflate).
  isal_zstream s{};
  isal_deflate_stateless_init(&s);
  s.level = static_cast<std::uint32_t>(level);
  s.level_buf = need > 0 ? level_buf_.data() : nullptr;
  s.level_buf_size = static_cast<std::uint32_t>(need);
  s.gzip_flag = IGZIP_DEFLATE;
  s.end_of_stream = 1;
  s.flush = NO_FLUSH;
  s.next_in = const_cast<unsigned char*>(in);  // not written: ISA-L's struct is not const-correct
  s.avail_in = static_cast<std::uint32_t>(n);
  s.next_out = out;
  s.avail_out = static_cast<std::uint32_t>(std::min<std::size_t>(cap, UINT32_MAX));
  const int r = isal_deflate_stateless(&s);
  clear_upper_vector_state();
  if (r == STATELESS_OVERFLOW) return std::nullopt;
  if (r != COMP_OK) throw std::runtime_error(fmt::format("ISA-L deflate (level {}): error {}", level, r));
  return s.total_out;
}

bool inflate_zlib(const unsigned char* in, std::size_t n_in, unsigned char* out, std::size_t n_out) {
  if (n_in > UINT32_MAX || n_out > UINT32_MAX) return false;
  // ISA-L's inflate state holds its decoding tables (about 20 kB): on the heap, once a thread.
  thread_local const std::unique_ptr<inflate_state> state = std::make_unique<inflate_state>();
  inflate_state& st = *state;
  isal_inflate_init(&st);
  st.next_in = const_cast<unsigned char*>(in);  // not written: ISA-L's struct is not const-correct
  st.avail_in = static_cast<std::uint32_t>(n_in);
  st.next_out = out;
  st.avail_out = static_cast<std::uint32_t>(n_out);
  st.crc_flag = ISAL_ZLIB;  // parses the header, checks the Adler-32 at the end
  const int r = isal_inflate_stateless(&st);
  clear_upper_vector_state();
  return r == ISAL_DECOMP_OK && st.total_out == n_out && st.avail_in == 0;
}

}  // namespace truss::util
