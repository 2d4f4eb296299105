// Progress of a campaign on rank 0: runs done (of all, including runs restored from a journal),
// failed, rate of this session and time left. On a terminal one line is rewritten in place
// (a few times per second); otherwise (a log file, CI) a full line every `interval_s`.
#pragma once
#include <chrono>
#include <cstdint>
#include <cstdio>

namespace truss::campaign {

enum class ProgressMode { automatic, terminal, lines, none };

class Progress {
 public:
  Progress(std::int64_t total, std::int64_t restored, ProgressMode mode, double line_interval_s, std::FILE* out = stderr);
  void update(std::int64_t done, std::int64_t failed);  // cheap: prints only when due
  void finish(std::int64_t done, std::int64_t failed);  // final line, always (unless none)

 private:
  void print(std::int64_t done, std::int64_t failed, bool final);
  std::int64_t total_, restored_;
  bool terminal_, enabled_;
  double interval_s_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_, last_;
};

}  // namespace truss::campaign
