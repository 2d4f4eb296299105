// The journal's writer thread (campaign/journal.hpp): frames reach the file whole and in order
// when far more than the writer's queue is handed over, periodic (asynchronous) flushes included,
// and a write error in the thread reaches the owner as an exception naming the journal.
#include <catch2/catch.hpp>

#include <sys/resource.h>

#include <atomic>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "campaign/journal.hpp"

using namespace truss::campaign;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "truss_journal_writer_tests";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  fs::remove(p);
  return p;
}

// Frame i's payload: its index spread over the bytes, so that a frame out of place or cut differs.
std::string payload(int i, std::size_t n) {
  std::string s(n, '\0');
  for (std::size_t k = 0; k < n; ++k) s[k] = static_cast<char>((i * 131 + static_cast<int>(k) * 7) & 0xff);
  return s;
}

// While alive: files of this process may not grow past `bytes` (writes fail with EFBIG), SIGXFSZ ignored.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &old_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit r = old_;
    r.rlim_cur = bytes;
    REQUIRE(setrlimit(RLIMIT_FSIZE, &r) == 0);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &old_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit old_{};
  void (*old_handler_)(int) = SIG_DFL;
};

}  // namespace

TEST_CASE("the journal's writer keeps every frame, in order, past its queue limit", "[campaign][journal]") {
  const std::string path = scratch("big.journal").string();
  const std::string text = "campaign W";
  // 4,000 frames of 5,000 bytes: 20 MB, more than twice the writer's queue limit: appending must wait for it.
  const int n = 4000;
  const std::size_t len = 5000;
  REQUIRE(n * len > 2 * Journal::kMaxQueuedBytes);
  std::vector<std::string> payloads;
  for (int i = 0; i < n; ++i) payloads.push_back(payload(i, len));
  {
    // Appending is a copy (several GB/s) and every 200th frame asks for an fdatasync (milliseconds):
    // buffers pile up behind the syncs, up to the queue limit.
    // Header: magic, version, text length, text, CRC; a frame: kind, length, CRC, payload.
    auto size_after = [&](int frames) { return 8 + 4 + 4 + text.size() + 4 + static_cast<std::size_t>(frames) * (1 + 4 + 4 + len); };
    std::atomic<std::uintmax_t> size_at_then{0};
    Journal j = Journal::create(path, text);
    for (int i = 0; i < n; ++i) {
      j.append(FrameKind::run, payloads[static_cast<std::size_t>(i)]);
      if (i == n / 2 - 1) j.flush_async([&] { size_at_then = fs::file_size(path); });  // runs once these are on disk
      else if (i % 200 == 199) j.flush_async();  // as the campaign's periodic flushes
    }
    j.flush();
    CHECK(size_at_then == size_after(n / 2));
    CHECK(fs::file_size(path) == size_after(n));
  }
  std::vector<JournalFrame> frames;
  std::size_t dropped = 1;
  Journal::resume(path, text, frames, dropped);
  CHECK(dropped == 0);
  REQUIRE(frames.size() == static_cast<std::size_t>(n));
  int wrong = 0;
  for (int i = 0; i < n; ++i) wrong += frames[static_cast<std::size_t>(i)].payload != payloads[static_cast<std::size_t>(i)];
  CHECK(wrong == 0);
  fs::remove(path);
}

TEST_CASE("a write error in the journal's writer reaches the owner", "[campaign][journal]") {
  const std::string path = scratch("full.journal").string();
  std::string first_error, second_error;
  {
    FileSizeLimit limit(1 << 20);  // 1 MiB: the first write-through buffer already goes past it
    Journal j = Journal::create(path, "campaign F");
    try {
      for (int i = 0; i < 2000; ++i) j.append(FrameKind::run, payload(i, 5000));
      j.flush();
    } catch (const std::runtime_error& e) {
      first_error = e.what();
    }
    try {
      j.flush();  // the error stays: nothing more is written after a failed write
    } catch (const std::runtime_error& e) {
      second_error = e.what();
    }
  }
  INFO(first_error);
  CHECK(first_error.find(path) != std::string::npos);
  CHECK(first_error.find("File too large") != std::string::npos);  // strerror(EFBIG)
  CHECK(second_error == first_error);
  // What is on disk is whole frames up to the limit and at most one torn one: resume keeps them.
  std::vector<JournalFrame> frames;
  std::size_t dropped = 0;
  Journal::resume(path, "campaign F", frames, dropped);
  CHECK(fs::file_size(path) <= (1u << 20));
  for (std::size_t i = 0; i < frames.size(); ++i) CHECK(frames[i].payload == payload(static_cast<int>(i), 5000));
  fs::remove(path);
}
