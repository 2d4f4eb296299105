// The journal (results/journal.hpp): its frames, torn tails and damaged middles, refusals, and a
// write error that stops it; the output's lock that guards it (results/lock_file.hpp).
#include <catch2/catch.hpp>

#include <sys/resource.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "results/journal.hpp"
#include "results/lock_file.hpp"
#include "util/bytes.hpp"
#include "util/isal.hpp"

using namespace truss::results;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
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

struct Read {
  std::vector<std::pair<FrameKind, std::string>> frames;
  JournalScan scan;
};

// Every good frame of an existing journal, and what finish_reading found past them.
Read read_back(const std::string& path, const std::string& text) {
  Read r;
  Journal j = Journal::open_existing(path, text);
  FrameKind k{};
  std::string_view p;
  std::size_t offset = 0;
  while (j.next_frame(k, p, offset)) r.frames.emplace_back(k, std::string(p));
  r.scan = j.finish_reading();
  return r;
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

TEST_CASE("a sealed frame: kind, length, the CRC-32 of kind and payload, the payload", "[campaign][journal]") {
  std::string msg = "xyz";  // a frame need not start at the beginning of its buffer
  const std::size_t start = begin_frame(msg);
  msg += "the payload";
  seal_frame(msg, start, FrameKind::run);
  const std::string_view f = std::string_view(msg).substr(start);
  CHECK(f.size() == kFrameHeader + 11);
  CHECK(f[0] == 'R');
  CHECK(truss::util::get_at<std::uint32_t>(f.data() + 1) == 11);
  CHECK(truss::util::get_at<std::uint32_t>(f.data() + 5) == truss::util::calc_crc32("Rthe payload"));
  const std::string two = std::string(f) + "next frame";
  const Frame r = read_frame(two);
  CHECK(r.kind == FrameKind::run);
  CHECK(r.payload == "the payload");
  CHECK(r.bytes.size() == f.size());
  CHECK_THROWS_AS(read_frame(f.substr(0, f.size() - 1)), std::runtime_error);  // cut
  CHECK_THROWS_AS(read_frame(f.substr(0, 4)), std::runtime_error);             // not even a header
}

TEST_CASE("the journal keeps every complete frame and drops a torn or damaged tail", "[campaign][journal]") {
  const std::string path = scratch("j1.journal").string();
  {
    Journal j = Journal::create(path, "campaign A");
    for (int i = 0; i < 5; ++i) j.append(FrameKind::run, std::string(100 + static_cast<std::size_t>(i), 'a' + i));
    std::string sealed;
    const std::size_t at = begin_frame(sealed);
    sealed += "made elsewhere";
    seal_frame(sealed, at, FrameKind::plan);
    j.append_frame(sealed);
    j.flush();
    CHECK_THROWS_AS(Journal::create(path, "campaign A"), std::runtime_error);  // exists
  }
  Read r = read_back(path, "campaign A");
  REQUIRE(r.frames.size() == 6);
  CHECK(r.scan.dropped_bytes == 0);
  CHECK(r.frames[3].second == std::string(103, 'd'));
  CHECK(r.frames[5] == std::make_pair(FrameKind::plan, std::string("made elsewhere")));

  // A frame cut short by a crash: dropped, the file truncated, appending continues after frame 6.
  const auto good_size = fs::file_size(path);
  { std::ofstream(path, std::ios::app | std::ios::binary) << std::string("R\x40\x00\x00\x00partial", 12); }
  {
    Journal j = Journal::open_existing(path, "campaign A");
    FrameKind k{};
    std::string_view p;
    std::size_t offset = 0;
    int n = 0;
    while (j.next_frame(k, p, offset)) ++n;
    CHECK(n == 6);
    CHECK(fs::file_size(path) == good_size + 12);  // nothing cut before finish_reading
    const JournalScan scan = j.finish_reading();
    CHECK(scan.dropped_bytes == 12);
    CHECK_FALSE(scan.damaged_middle());
    CHECK(fs::file_size(path) == good_size);
    j.append(FrameKind::heartbeat, "hb");
  }  // the destructor writes the buffer out
  r = read_back(path, "campaign A");
  CHECK(r.frames.size() == 7);
  CHECK(r.frames.back().first == FrameKind::heartbeat);

  // One flipped byte inside frame 3: frames 1-2 survive; the valid run frames after the damage are
  // counted (a damaged middle, not a torn tail).
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    const auto header = 8 + 4 + 4 + std::string("campaign A").size() + 4;
    f.seekp(static_cast<std::streamoff>(header + 2 * (9 + 100) + 9 + 50 + 2));
    f.put('#');
  }
  r = read_back(path, "campaign A");
  CHECK(r.frames.size() == 2);
  CHECK(r.scan.records_kept == 2);
  CHECK(r.scan.records_dropped == 2);  // frames 4 and 5 (frame 6 is a plan, 7 a heartbeat)
  CHECK(r.scan.damaged_middle());
  CHECK_THAT(r.scan.describe(path), Catch::Contains("damaged in the middle"));

  // Another campaign's journal is refused.
  CHECK_THROWS_AS(Journal::open_existing(path, "campaign B"), JournalRefused);

  // A header cut one byte before its end (magic 8, version 4, length 4, text, CRC 4): truncated,
  // not a version mismatch (the version it holds is this program's).
  const auto header = 8 + 4 + 4 + std::string("campaign A").size() + 4;
  fs::resize_file(path, header - 1);
  try {
    (void)Journal::open_existing(path, "campaign A");
    FAIL("a cut header was read");
  } catch (const std::runtime_error& e) {
    CHECK_THAT(std::string(e.what()), Catch::Contains(fmt::format("truncated journal header ({} bytes of the file, the "
                                                                  "header says {})", header - 1, header)) &&
                                          !Catch::Contains("version"));
  }
}

TEST_CASE("frames written through many buffers come back whole and in order", "[campaign][journal]") {
  const std::string path = scratch("big.journal").string();
  {
    Journal j = Journal::create(path, "campaign W");
    for (int i = 0; i < 1000; ++i) j.append(FrameKind::run, payload(i, 4473));  // 4.5 MB: four write-throughs
    j.flush();
  }
  const Read r = read_back(path, "campaign W");
  REQUIRE(r.frames.size() == 1000);
  for (int i = 0; i < 1000; ++i) CHECK(r.frames[static_cast<std::size_t>(i)].second == payload(i, 4473));
  fs::remove(path);
}

TEST_CASE("a write error stops the journal: the error, then nothing more written", "[campaign][journal]") {
  const std::string path = scratch("full.journal").string();
  std::string first_error, second_error;
  {
    FileSizeLimit limit(1 << 20);  // 1 MiB: the first write-through already goes past it
    Journal j = Journal::create(path, "campaign F");
    try {
      for (int i = 0; i < 2000; ++i) j.append(FrameKind::run, payload(i, 5000));
      j.flush();
    } catch (const std::runtime_error& e) {
      first_error = e.what();
    }
    try {
      j.flush();
    } catch (const std::runtime_error& e) {
      second_error = e.what();
    }
  }
  INFO(first_error);
  CHECK(first_error.find(path) != std::string::npos);
  CHECK(first_error.find("File too large") != std::string::npos);  // strerror(EFBIG)
  CHECK(second_error == first_error);
  // What is on disk is whole frames up to the limit and at most one torn one: they read back.
  const Read r = read_back(path, "campaign F");
  CHECK(fs::file_size(path) <= (1u << 20));
  CHECK(r.frames.size() > 100);
  for (std::size_t i = 0; i < r.frames.size(); ++i) CHECK(r.frames[i].second == payload(static_cast<int>(i), 5000));
  fs::remove(path);
}

TEST_CASE("a lock file: one holder, named to the others, the file gone when let go", "[campaign][journal]") {
  const std::string path = scratch(".out.h5.lock").string();
  {
    std::ofstream(path) << "PID 1 on a host that rebooted\n";  // a dead holder's file: taken over
    const truss::results::LockFile lock(path);
    const std::string me = "PID " + std::to_string(::getpid()) + " on ";
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);
    CHECK(line.rfind(me, 0) == 0);
    // flock() locks belong to an open file: a second one is refused, in this process as in another.
    CHECK_THROWS_MATCHES(truss::results::LockFile(path), truss::results::LockHeld, Catch::Message(line));
  }
  CHECK_FALSE(fs::exists(path));
  const truss::results::LockFile again(path);
  CHECK(fs::exists(path));
}
