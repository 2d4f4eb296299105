// Reading a user's input file (scene or campaign) whole, bounded in size, with errors that name it.
#include <array>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "io/scene_toml.hpp"

namespace truss::io {

std::string read_input_file(const std::string& path, const char* what, std::size_t max_bytes) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(fmt::format("error: {}: cannot read {}: is a directory", path, what));
  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;
    throw InputError(fmt::format("error: {}: cannot read {}: {}", path, what, err ? std::strerror(err) : "cannot open"));
  }
  // Read in blocks until the end or past max_bytes: a device such as /dev/zero or a huge file is
  // refused, not slurped, and a small file costs its size, not max_bytes.
  std::string text;
  std::array<char, 1 << 16> block;
  do {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    text.append(block.data(), static_cast<std::size_t>(in.gcount()));
    if (text.size() > max_bytes)
      throw InputError(fmt::format("error: {}: cannot read {}: larger than the limit of {} bytes ({} MiB)", path,
                                   what, max_bytes, max_bytes >> 20));
  } while (in);
  if (in.bad()) throw InputError(fmt::format("error: {}: cannot read {}: read error", path, what));
  return text;
}

}  // namespace truss::io
