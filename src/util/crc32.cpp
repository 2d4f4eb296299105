#include "util/crc32.hpp"

#include <zlib.h>

#include <algorithm>
#include <climits>

namespace truss::util {

std::uint32_t calc_crc32(std::string_view bytes, std::uint32_t crc) {
  uLong c = crc;
  const auto* p = reinterpret_cast<const Bytef*>(bytes.data());
  // zlib takes a uInt length: pieces of at most 1 GiB.
  for (std::size_t left = bytes.size(); left > 0;) {
    const std::size_t n = std::min<std::size_t>(left, std::size_t{1} << 30);
    c = ::crc32(c, p, static_cast<uInt>(n));
    p += n;
    left -= n;
  }
  return static_cast<std::uint32_t>(c);
}

}  // namespace truss::util
