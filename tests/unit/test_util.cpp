// The general-purpose pieces of src/util: CRC-32 against the published check value and its
// continuation, byte images and the reader's refusals.
#include <catch2/catch.hpp>

#include <cstdint>
#include <limits>
#include <string>

#include "util/bytes.hpp"
#include "util/isal.hpp"

using namespace truss::util;

TEST_CASE("CRC-32: the check value of the standard, and a CRC continued over pieces", "[util]") {
  // "123456789" -> 0xCBF43926: the check value of CRC-32/ISO-HDLC (zlib, PNG, gzip), published with
  // the algorithm's parameters, independent of any implementation here.
  CHECK(calc_crc32("123456789") == 0xCBF43926u);
  CHECK(calc_crc32("") == 0u);
  const std::string a = "a record's head", b = std::string(70000, '\x5a') + "and its payload";
  CHECK(calc_crc32(b, calc_crc32(a)) == calc_crc32(a + b));
  std::string flipped = a + b;
  flipped[40000] ^= 1;
  CHECK(calc_crc32(flipped) != calc_crc32(a + b));
}

TEST_CASE("byte images: values back as they were put, any alignment; a short read is refused", "[util]") {
  std::string s = "x";  // the values that follow are not aligned
  put(s, std::int64_t{-5});
  put(s, 2.5);
  put(s, std::uint32_t{7});
  s += "tail";
  CHECK(s.size() == 1 + 8 + 8 + 4 + 4);
  CHECK(get_at<std::int64_t>(s.data() + 1) == -5);
  CHECK(get_at<double>(s.data() + 9) == 2.5);
  // Little-endian: the lowest byte first.
  CHECK(static_cast<unsigned char>(s[17]) == 7);
  put_at(s.data() + 9, std::numeric_limits<double>::infinity());
  CHECK(get_at<double>(s.data() + 9) == std::numeric_limits<double>::infinity());

  ByteReader r(std::string_view(s).substr(1), "a test image");
  CHECK(r.get<std::int64_t>() == -5);
  CHECK(r.get<double>() == std::numeric_limits<double>::infinity());
  CHECK(r.get<std::uint32_t>() == 7);
  CHECK(r.left() == 4);
  CHECK_THROWS_WITH(r.expect_end(), "a test image has 4 bytes past its end");
  CHECK_THROWS_WITH(r.get<double>(), "a test image cut short: 4 bytes left, 8 needed");
  CHECK(r.get_bytes(4) == "tail");
  CHECK_NOTHROW(r.expect_end());
  // At the boundary: 7 bytes hold no double, 8 do.
  ByteReader seven(std::string_view(s).substr(1, 7), "seven bytes");
  CHECK_THROWS_WITH(seven.get<double>(), "seven bytes cut short: 7 bytes left, 8 needed");
  ByteReader eight(std::string_view(s).substr(1, 8), "eight bytes");
  CHECK(eight.get<std::int64_t>() == -5);
  CHECK_THROWS(eight.get_bytes(1));
}
