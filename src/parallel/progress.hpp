// Progress of a campaign on rank 0: a start banner (campaign, runs, ranks, output), then runs done
// (of all, including runs restored from a journal) with the count of every outcome by its status
// name (a stall is an outcome of the physics, not a failure of the program), the rate of this
// session and the time left. On a terminal one line is rewritten in place (5 times a second);
// otherwise (a log file, CI) a full line every `interval_s`. Under mpirun rank 0's stderr is a
// pipe even when mpirun writes to a terminal (Open MPI forwards it), so `automatic` gives lines
// there: pass --progress tty (scripts/run_main.sh does when its stderr is a terminal).
#pragma once
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "results/campaign_file.hpp"

namespace truss::parallel {

enum class ProgressMode { automatic, terminal, lines, none };

using results::StatusCounts;

// "9990 ok, 10 stall" (the nonzero counts, by to_string(RunStatus) name, in enum order).
std::string format_status_counts(const StatusCounts& counts);

class Progress {
 public:
  // total: the runs planned so far (a method that adds rounds adds to it: set_total).
  Progress(std::int64_t total, std::int64_t restored, ProgressMode mode, double line_interval_s,
           std::FILE* out = stderr);
  void banner(const std::string& campaign, int ranks, const std::string& output);
  void set_total(std::int64_t total) { total_ = total; }
  // Cheap unless due: `counts` is called only when a line is printed.
  template <class CountsFn>
  void update(std::int64_t done, CountsFn&& counts) {
    if (!enabled_ || !due()) return;
    print(done, counts(), false);
  }
  void finish(std::int64_t done, const StatusCounts& counts);  // final line, always (unless none)
  bool terminal() const { return terminal_; }

 private:
  bool due();
  void print(std::int64_t done, const StatusCounts& counts, bool final);
  std::int64_t total_, restored_;
  bool terminal_, enabled_;
  double interval_s_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_, last_;
};

// The end summary: each output's nominal value and its campaign P99.865 and maximum.
void print_design_summary(std::FILE* out, const std::vector<results::DesignValue>& values);

}  // namespace truss::parallel
