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
  // A method of rounds (subset simulation): the line names the stage ("level 2 (margin <= ...)")
  // and counts the runs so far against `cap` (the most the campaign may make) instead of against
  // the rounds proposed so far; its time left is then an upper bound. Empty stage, 0: plain line.
  void set_stage(std::string stage, std::int64_t cap) {
    stage_ = std::move(stage);
    cap_ = cap;
  }
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
  std::string stage_;
  std::int64_t cap_ = 0;
  bool terminal_, enabled_;
  double interval_s_;
  std::FILE* out_;
  std::chrono::steady_clock::time_point start_, last_;
};

// Ok runs an upper bound of P99.865 needs at 95 % confidence: the smallest n with
// 1 - 0.99865^n >= 0.95 (2218; the load report's design-load table uses the same bound).
std::int64_t calc_runs_needed_p99_865();
// The values, each P99.865 from fewer ok runs than that flagged as too few.
void print_design_summary(std::FILE* out, const std::vector<results::DesignValue>& values);

// The end of a campaign: whether its runs are usable. When most runs (more than half) are invalid
// input, the dispersions give scenes the model refuses: prints an error with the count and an
// example reason (`example`: a run's message) and returns false (the command then exits non-zero;
// the results file stays written, failed runs are data). Some invalid runs: a warning, true.
bool print_campaign_verdict(std::FILE* out, const StatusCounts& counts, const std::string& example);

}  // namespace truss::parallel
