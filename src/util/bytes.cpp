#include "util/bytes.hpp"

#include <fmt/format.h>

namespace truss::util {

void ByteReader::need(std::size_t n) const {
  if (left() < n) throw std::runtime_error(fmt::format("{} cut short: {} bytes left, {} needed", what_, left(), n));
}

void ByteReader::expect_end() const {
  if (left() != 0) throw std::runtime_error(fmt::format("{} has {} bytes past its end", what_, left()));
}

}  // namespace truss::util
