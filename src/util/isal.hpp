// Every ISA-L kernel the project calls, behind one door: CRC-32 (every journal frame), Adler-32,
// raw DEFLATE (the results file's chunks) and the zlib inflate that reads them back. Each function
// clears the vector state ISA-L's AVX2 / AVX-512 kernels leave behind before it returns, so no
// caller has to remember it: those kernels return with the upper halves of the YMM/ZMM registers
// dirty, and the model's scalar SSE2 code that follows pays for that state on every instruction
// until it is cleared (VZEROUPPER where the CPU has AVX; the cost: docs/benchmarks.md, "The vector
// state after ISA-L's kernels"). Clearing leaves every register value a caller can hold across a
// call unchanged (the x86-64 ABI saves no vector register across calls, and VZEROUPPER keeps the
// low 128 bits).
#pragma once
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace truss::util {

// The CRC-32 of `bytes` (the zlib / PNG / gzip polynomial, as zlib's crc32() computes it),
// continuing from `crc` (the CRC of the bytes before them; 0 to start).
std::uint32_t calc_crc32(std::string_view bytes, std::uint32_t crc = 0);

// The Adler-32 of `bytes` (RFC 1950), continuing from `adler` (1 to start).
std::uint32_t calc_adler32(const unsigned char* bytes, std::size_t n, std::uint32_t adler = 1);

// ISA-L's stateless igzip: one raw DEFLATE stream (RFC 1951, its last block final) at a time. It
// keeps the work space of ISA-L's levels 2 and 3 between calls.
class Deflater {
 public:
  // in[0, n) deflated at igzip level 1..3 into out[0, cap): the bytes written, or nothing when the
  // stream does not fit in cap. Throws std::length_error for n >= 4 GiB (ISA-L's counters are 32
  // bits), std::runtime_error naming ISA-L's error for anything else that fails.
  std::optional<std::size_t> deflate(const unsigned char* in, std::size_t n, int level, unsigned char* out,
                                     std::size_t cap);

 private:
  std::vector<unsigned char> level_buf_;
};

// One zlib stream (RFC 1950: header, DEFLATE data, Adler-32) inflated by ISA-L into exactly
// out[0, n_out): true when the stream is whole, its checksum right and it holds n_out bytes, false
// for anything else (a damaged or foreign stream, a size that does not match).
bool inflate_zlib(const unsigned char* in, std::size_t n_in, unsigned char* out, std::size_t n_out);

}  // namespace truss::util
