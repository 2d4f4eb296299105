#include "util/crc32.hpp"

#include <isa-l/crc.h>

namespace truss::util {

// ISA-L's CRC-32 (the gzip/zlib polynomial, folded with carry-less multiplication where the CPU has
// it): 0.11 us for a 4.7 kB Table-1 record against libdeflate's 0.33 and zlib 1.2.13's 1.2, the
// same values. Every record is checksummed twice (sealed by its rank, checked by rank 0).
std::uint32_t calc_crc32(std::string_view bytes, std::uint32_t crc) {
  return crc32_gzip_refl(crc, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size());
}

}  // namespace truss::util
