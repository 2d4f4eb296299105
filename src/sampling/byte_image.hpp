// byte_image.hpp — the byte images of the sampling library's round plans and states: native
// little-endian integers and IEEE-754 doubles appended in order; a reader that refuses a cut or
// overlong buffer, and a count its rest cannot hold, before allocating for it.
#pragma once
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

namespace truss::sampling::detail {

struct ByteWriter {
  std::string out;
  template <class T>
  void put(T v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  template <class T>
  void put_all(const std::vector<T>& v) {
    put(static_cast<std::uint64_t>(v.size()));
    out.append(reinterpret_cast<const char*>(v.data()), sizeof(T) * v.size());
  }
};

struct ByteReader {
  std::string_view in;
  const char* what;
  template <class T>
  T get() {
    if (in.size() < sizeof(T)) throw std::runtime_error(fmt::format("{}: cut short ({} bytes left)", what, in.size()));
    T v;
    std::memcpy(&v, in.data(), sizeof v);
    in.remove_prefix(sizeof v);
    return v;
  }
  // A count of items of `size` bytes each that the rest of the buffer can hold.
  std::size_t get_count(std::size_t size) {
    const auto n = get<std::uint64_t>();
    if (n > in.size() / size) throw std::runtime_error(fmt::format("{}: {} items in {} bytes", what, n, in.size()));
    return static_cast<std::size_t>(n);
  }
  template <class T>
  std::vector<T> get_all() {
    std::vector<T> v(get_count(sizeof(T)));
    if (!v.empty()) std::memcpy(v.data(), in.data(), sizeof(T) * v.size());
    in.remove_prefix(sizeof(T) * v.size());
    return v;
  }
  void expect_end() {
    if (!in.empty()) throw std::runtime_error(fmt::format("{}: {} bytes past the end", what, in.size()));
  }
};

}  // namespace truss::sampling::detail
