// CRC-32 (the zlib / PNG / gzip polynomial, as zlib's crc32() computes it): the checksum of every
// frame of the results journal, so that a torn or damaged frame is found when it is read back.
#pragma once
#include <cstdint>
#include <string_view>

namespace truss::util {

// The CRC-32 of `bytes`, continuing from `crc` (the CRC of the bytes before them; 0 to start).
std::uint32_t calc_crc32(std::string_view bytes, std::uint32_t crc = 0);

}  // namespace truss::util
