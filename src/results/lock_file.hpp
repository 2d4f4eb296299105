// An exclusive lock held while the object lives: flock() on a file (created if missing) that holds
// its holder's "PID n on HOST". The kernel drops the lock when its process ends, kill -9 included,
// so the file of a dead holder is simply taken over. The holder removes the file when it lets go;
// a process that opened the file just before sees, once it has the lock, that its file is no
// longer the path's (removed, or another one made since) and starts again, so that two processes
// never both believe they hold the lock of one path.
#pragma once
#include <stdexcept>
#include <string>

namespace truss::results {

// Another live process holds the lock; what() names it as its file does ("PID 4242 on node7").
struct LockHeld : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class LockFile {
 public:
  // Takes the lock of `path` without waiting. Throws LockHeld if another process holds it, and
  // std::runtime_error if the file cannot be created or locked.
  explicit LockFile(std::string path);
  ~LockFile();  // removes the file, then lets go of the lock
  LockFile(const LockFile&) = delete;
  LockFile& operator=(const LockFile&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace truss::results
