// Little-endian byte images of plain values: what the results journal, a run record, a round plan
// and the MPI messages are made of. This project runs on little-endian machines only (checked at
// build time), so a value's image is its memory.
#pragma once
#include <bit>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

namespace truss::util {

static_assert(std::endian::native == std::endian::little, "byte images are little-endian");

// Appends the bytes of v.
template <class T>
void put(std::string& out, const T& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

// Writes the bytes of v at p (any alignment).
template <class T>
void put_at(char* p, const T& v) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::memcpy(p, &v, sizeof(T));
}

// The value whose bytes are at p (any alignment).
template <class T>
T get_at(const char* p) {
  static_assert(std::is_trivially_copyable_v<T>);
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// Reads values in order from a byte string; reading past its end throws std::runtime_error naming
// what was read ("a round plan cut short: 3 bytes left, 8 needed").
class ByteReader {
 public:
  ByteReader(std::string_view bytes, const char* what) : bytes_(bytes), what_(what) {}
  template <class T>
  T get() {
    need(sizeof(T));
    const T v = get_at<T>(bytes_.data() + at_);
    at_ += sizeof(T);
    return v;
  }
  std::string_view get_bytes(std::size_t n) {
    need(n);
    const std::string_view v = bytes_.substr(at_, n);
    at_ += n;
    return v;
  }
  std::size_t left() const { return bytes_.size() - at_; }
  // Throws unless every byte has been read.
  void expect_end() const;

 private:
  void need(std::size_t n) const;
  std::string_view bytes_;
  const char* what_;
  std::size_t at_ = 0;
};

}  // namespace truss::util
