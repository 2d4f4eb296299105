#include "results/lock_file.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <fmt/format.h>

namespace truss::results {

namespace {

[[noreturn]] void fail_errno(const char* what, const std::string& path, int err) {
  throw std::runtime_error(fmt::format("{} {}: {}", what, path, std::strerror(err)));
}

// What the holder wrote into its lock file ("" if nothing yet: it has just made the file).
std::string read_holder(int fd) {
  char buf[256];
  const ssize_t n = ::pread(fd, buf, sizeof buf, 0);
  std::string s(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
  while (!s.empty() && (s.back() == '\n' || s.back() == '\0')) s.pop_back();
  return s;
}

// True if `fd` is the file at `path` now (not one removed or replaced since it was opened).
bool is_current(int fd, const std::string& path) {
  struct stat open_file{}, at_path{};
  if (::fstat(fd, &open_file) != 0) fail_errno("cannot stat lock file", path, errno);
  if (::stat(path.c_str(), &at_path) != 0) {
    if (errno == ENOENT) return false;
    fail_errno("cannot stat lock file", path, errno);
  }
  return open_file.st_dev == at_path.st_dev && open_file.st_ino == at_path.st_ino;
}

}  // namespace

LockFile::LockFile(std::string path) : path_(std::move(path)) {
  for (;;) {
    const int fd = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) fail_errno("cannot create lock file", path_, errno);
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      const std::string holder = read_holder(fd);
      ::close(fd);
      if (err == EWOULDBLOCK) throw LockHeld(holder.empty() ? "a process that is just starting" : holder);
      fail_errno("cannot lock", path_, err);
    }
    if (is_current(fd, path_)) {
      fd_ = fd;
      break;
    }
    ::close(fd);  // its holder removed it as we locked it: lock the path's file now
  }
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  const std::string me = fmt::format("PID {} on {}\n", static_cast<long>(::getpid()), host);
  // Only a name for the refusal of others: the lock holds without it (on a full disk, say).
  if (::ftruncate(fd_, 0) == 0) (void)!::pwrite(fd_, me.data(), me.size(), 0);
}

LockFile::~LockFile() {
  ::unlink(path_.c_str());  // while still holding the lock: see the header
  ::close(fd_);
}

}  // namespace truss::results
