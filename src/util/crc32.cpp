#include "util/crc32.hpp"

#include <isa-l/crc.h>

#include "util/vector_state.hpp"

namespace truss::util {

// ISA-L's CRC-32 (the gzip/zlib polynomial, reflected, as zlib's crc32: the same values; folded with
// carry-less multiplication where the CPU has it; docs/benchmarks.md). Every record is checksummed
// twice (sealed by its rank, checked by rank 0).
std::uint32_t calc_crc32(std::string_view bytes, std::uint32_t crc) {
  const std::uint32_t out = crc32_gzip_refl(crc, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
  clear_upper_vector_state();  // ISA-L's kernel leaves the vector state dirty (util/vector_state.hpp)
  return out;
}

}  // namespace truss::util
