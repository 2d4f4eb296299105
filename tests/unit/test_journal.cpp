// The journal (campaign/journal.hpp): its file format, torn tails, and its writer thread (queue
// limit, frames written from the memory they arrived in, flush callbacks, write errors). This file
// depends on the journal alone, so that scripts/sanitize.sh also runs it under ThreadSanitizer
// (journal_tsan: the writer is the only thread the campaign starts).
#include <catch2/catch.hpp>

#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "campaign/journal.hpp"

using namespace truss::campaign;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  // Per process: the plain and the ThreadSanitizer builds of these tests may run at once.
  const fs::path dir = fs::temp_directory_path() / ("truss_journal_tests_" + std::to_string(::getpid()));
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

TEST_CASE("the journal keeps every complete frame and drops a torn or damaged tail", "[campaign][journal]") {
  const std::string path = scratch("j1.journal").string();
  {
    Journal j = Journal::create(path, "campaign A");
    for (int i = 0; i < 5; ++i) j.append(FrameKind::run, std::string(100 + i, static_cast<char>('a' + i)));
    j.flush();
    CHECK_THROWS_AS(Journal::create(path, "campaign A"), std::runtime_error);  // exists
  }
  std::vector<JournalFrame> frames;
  std::size_t dropped = 1;
  { Journal::resume(path, "campaign A", frames, dropped); }
  REQUIRE(frames.size() == 5);
  CHECK(dropped == 0);
  CHECK(frames[3].payload == std::string(103, 'd'));

  // A frame cut short by a crash: dropped, the file truncated, appending continues after frame 5.
  const auto good_size = fs::file_size(path);
  { std::ofstream(path, std::ios::app | std::ios::binary) << std::string("R\x40\x00\x00\x00partial", 12); }
  {
    Journal j = Journal::resume(path, "campaign A", frames, dropped);
    CHECK(frames.size() == 5);
    CHECK(dropped == 12);
    CHECK(fs::file_size(path) == good_size);
    j.append(FrameKind::heartbeat, "hb");
  }
  Journal::resume(path, "campaign A", frames, dropped);
  CHECK(frames.size() == 6);
  CHECK(frames.back().kind == FrameKind::heartbeat);

  // One flipped byte inside frame 3: frames 1-2 survive, the rest is recomputed on resume.
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    const auto header = 8 + 4 + 4 + std::string("campaign A").size() + 4;
    f.seekp(static_cast<std::streamoff>(header + 2 * (9 + 100) + 9 + 50 + 2));
    f.put('#');
  }
  Journal::resume(path, "campaign A", frames, dropped);
  CHECK(frames.size() == 2);
  CHECK(dropped > 0);

  // Another campaign's journal, or one that a live process holds, is refused.
  CHECK_THROWS_AS(Journal::resume(path, "campaign B", frames, dropped), JournalRefused);
  {
    Journal held = Journal::resume(path, "campaign A", frames, dropped);
    CHECK_THROWS_AS(Journal::resume(path, "campaign A", frames, dropped), JournalRefused);
    CHECK_THROWS_AS(Journal::remove_unused(path), JournalRefused);
  }
  Journal::remove_unused(path);
  CHECK(!fs::exists(path));
}

// The writer thread: frames reach the file whole and in order when far more than its queue is
// handed over, the periodic flushes' callbacks run after the sync, and a write error in the thread
// reaches the owner as an exception naming the journal.
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

TEST_CASE("frames journaled from the memory they arrived in: in order, that memory released once written",
          "[campaign][journal]") {
  const std::string path = scratch("owned.journal").string();
  const std::string text = "campaign O";
  auto sealed = [](int i, std::size_t len) {
    std::string f(Journal::kFrameHeader, '\0');
    f += payload(i, len);
    Journal::seal_frame(f, FrameKind::run);
    return f;
  };
  // 300 messages as a worker sends them (a prefix, then per frame a u32 length and the frame), of
  // 10 frames of 3,000 bytes: 9 MB, past the writer's queue limit; between them a frame appended
  // (copied) and a heartbeat, as rank 0's own runs and its flushes.
  const int messages = 300, per = 10;
  const std::size_t len = 3000;
  std::vector<std::string> want;
  std::vector<std::weak_ptr<const char[]>> held;
  {
    Journal j = Journal::create(path, text);
    int id = 0;
    for (int m = 0; m < messages; ++m) {
      std::string bytes = "PREFIX";
      std::vector<std::size_t> at;
      for (int k = 0; k < per; ++k, ++id) {
        const std::string f = sealed(id, len);
        const auto n = static_cast<std::uint32_t>(f.size());
        bytes.append(reinterpret_cast<const char*>(&n), 4);
        at.push_back(bytes.size());
        bytes += f;
        want.push_back(payload(id, len));
      }
      std::shared_ptr<char[]> msg(new char[bytes.size()]);
      std::memcpy(msg.get(), bytes.data(), bytes.size());
      std::vector<std::string_view> views;
      for (std::size_t a : at) views.emplace_back(msg.get() + a, Journal::kFrameHeader + len);
      held.push_back(msg);
      j.append_frames(std::move(msg), views);
      j.append_frame(sealed(id, 100));
      want.push_back(payload(id++, 100));
      j.append(FrameKind::heartbeat, "beat");
      if (m % 50 == 49) j.flush_async();
    }
    j.flush();
    int alive = 0;
    for (const auto& w : held) alive += !w.expired();
    CHECK(alive == 0);  // the writer let go of every message once written
    // A frame whose length field does not match what it is: refused, nothing queued.
    std::string bad = sealed(0, 10);
    bad.pop_back();
    CHECK_THROWS_WITH(j.append_frame(bad), Catch::Contains("not a sealed journal frame"));
    std::shared_ptr<char[]> owner(new char[bad.size()]);
    std::memcpy(owner.get(), bad.data(), bad.size());
    CHECK_THROWS_WITH(j.append_frames(owner, {std::string_view(owner.get(), bad.size())}), Catch::Contains("not a sealed journal frame"));
  }
  std::vector<JournalFrame> frames;
  std::size_t dropped = 1;
  Journal::resume(path, text, frames, dropped);
  CHECK(dropped == 0);
  std::vector<std::string> runs;
  int beats = 0;
  for (const auto& f : frames) {
    if (f.kind == FrameKind::run) runs.push_back(f.payload);
    beats += f.kind == FrameKind::heartbeat;
  }
  CHECK(beats == messages);
  REQUIRE(runs.size() == want.size());
  int wrong = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) wrong += runs[i] != want[i];
  CHECK(wrong == 0);
  // Order across kinds: each heartbeat right after its message's frames and the copied frame.
  REQUIRE(frames.size() > static_cast<std::size_t>(per + 1));
  CHECK(frames[static_cast<std::size_t>(per + 1)].kind == FrameKind::heartbeat);
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
