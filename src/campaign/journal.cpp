#include "campaign/journal.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>
#include <zlib.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace truss::campaign {

namespace {

constexpr char kMagic[8] = {'T', 'R', 'U', 'S', 'S', 'J', 'N', 'L'};
constexpr std::uint32_t kVersion = 1;

[[noreturn]] void fail_errno(const std::string& what, const std::string& path) {
  throw std::runtime_error(fmt::format("{} {}: {}", what, path, std::strerror(errno)));
}

template <class T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
bool get(std::string_view b, std::size_t& at, T& v) {
  if (b.size() - at < sizeof(T)) return false;
  std::memcpy(&v, b.data() + at, sizeof(T));
  at += sizeof(T);
  return true;
}

void write_all(int fd, std::string_view data, const std::string& path) {
  while (!data.empty()) {
    const ssize_t n = ::write(fd, data.data(), data.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_errno("cannot write journal", path);
    }
    data.remove_prefix(static_cast<std::size_t>(n));
  }
}

void lock_or_refuse(int fd, const std::string& path) {
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return;
  const int err = errno;
  ::close(fd);
  if (err == EWOULDBLOCK)
    throw JournalRefused(fmt::format("{} is in use by another running truss-campaign (perhaps ranks of a killed "
                                     "mpirun are still running: stop them first)", path));
  errno = err;
  fail_errno("cannot lock journal", path);
}

}  // namespace

void Journal::remove_unused(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail_errno("cannot open journal", path);
  lock_or_refuse(fd, path);
  if (::unlink(path.c_str()) != 0) fail_errno("cannot remove journal", path);
  ::close(fd);
}

std::uint32_t crc32_of(std::string_view bytes) {
  return static_cast<std::uint32_t>(
      ::crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

Journal Journal::create(const std::string& path, const std::string& campaign_text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) fail_errno("cannot create journal", path);
  lock_or_refuse(fd, path);
  Journal j(path, fd);
  std::string h(kMagic, sizeof kMagic);
  put(h, kVersion);
  put(h, static_cast<std::uint32_t>(campaign_text.size()));
  h += campaign_text;
  put(h, crc32_of(campaign_text));
  j.buffer_ = std::move(h);
  j.flush();
  return j;
}

Journal Journal::resume(const std::string& path, const std::string& campaign_text, std::vector<JournalFrame>& frames,
                        std::size_t& dropped_bytes) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) fail_errno("cannot open journal", path);
  lock_or_refuse(fd, path);
  Journal j(path, fd);
  std::string all;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_errno("cannot read journal", path);
    }
    if (n == 0) break;
    all.append(buf, static_cast<std::size_t>(n));
  }
  std::size_t at = 0;
  std::uint32_t version = 0, len = 0, crc = 0;
  if (all.size() < sizeof kMagic || std::memcmp(all.data(), kMagic, sizeof kMagic) != 0)
    throw std::runtime_error(fmt::format("{} is not a truss-campaign journal", path));
  at = sizeof kMagic;
  if (!get(all, at, version) || version != kVersion || !get(all, at, len) || all.size() - at < len)
    throw std::runtime_error(fmt::format("{}: unreadable journal header", path));
  const std::string_view text(all.data() + at, len);
  at += len;
  if (!get(all, at, crc) || crc != crc32_of(text)) throw std::runtime_error(fmt::format("{}: damaged journal header", path));
  if (text != campaign_text)
    throw JournalRefused(fmt::format("{} belongs to a different campaign (resolved campaign text differs); "
                                      "finish it with the same campaign file and --set options, or start over with --force", path));
  frames.clear();
  std::size_t good = at;
  for (;;) {
    std::uint8_t kind = 0;
    std::uint32_t n = 0, c = 0;
    std::size_t p = good;
    if (!get(all, p, kind) || !get(all, p, n) || !get(all, p, c) || all.size() - p < n) break;
    std::string payload(all.data() + p, n);
    std::string framed(1, static_cast<char>(kind));
    framed += payload;
    if (c != crc32_of(framed)) break;
    frames.push_back({static_cast<FrameKind>(kind), std::move(payload)});
    good = p + n;
  }
  dropped_bytes = all.size() - good;
  if (dropped_bytes > 0 && ::ftruncate(fd, static_cast<off_t>(good)) != 0) fail_errno("cannot truncate journal", path);
  if (::lseek(fd, static_cast<off_t>(good), SEEK_SET) < 0) fail_errno("cannot seek journal", path);
  return j;
}

Journal::Journal(Journal&& o) noexcept : path_(std::move(o.path_)), fd_(o.fd_), buffer_(std::move(o.buffer_)) { o.fd_ = -1; }

Journal::~Journal() {
  if (fd_ >= 0) {
    try {
      flush();
    } catch (...) {
    }
    ::close(fd_);
  }
}

void Journal::append(FrameKind kind, std::string_view payload) {
  // CRC-32 of kind + payload, without building that string.
  const auto k = static_cast<Bytef>(kind);
  uLong crc = ::crc32(0L, &k, 1);
  crc = ::crc32(crc, reinterpret_cast<const Bytef*>(payload.data()), static_cast<uInt>(payload.size()));
  put(buffer_, static_cast<std::uint8_t>(kind));
  put(buffer_, static_cast<std::uint32_t>(payload.size()));
  put(buffer_, static_cast<std::uint32_t>(crc));
  buffer_.append(payload);
  // Bounded memory: hand full buffers to the kernel (no sync; flush() syncs).
  if (buffer_.size() >= kWriteThrough) {
    write_all(fd_, buffer_, path_);
    buffer_.clear();
  }
}

void Journal::flush() {
  if (buffer_.empty()) return;
  write_all(fd_, buffer_, path_);
  buffer_.clear();
  if (::fdatasync(fd_) != 0) fail_errno("cannot sync journal", path_);
}

void Journal::close_and_remove() {
  flush();
  ::close(fd_);
  fd_ = -1;
  if (::unlink(path_.c_str()) != 0) fail_errno("cannot remove journal", path_);
}

}  // namespace truss::campaign
