// truss-campaign's output: the options that concern it, rank 0's state from its first check to the
// end (the output's lock, the results file, the journal, the collector), and what every rank must
// know of it before the session (where the file and the journals are, which chunks rank 0 keeps).
#pragma once
#include <mpi.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "parallel/engine.hpp"
#include "parallel/owner.hpp"
#include "results/lock_file.hpp"

namespace truss::parallel {

struct CommandOptions {
  std::string campaign_path;
  std::string output_path;
  std::vector<std::string> sets;
  bool resume = false;
  bool force = false;
  bool dry_run = false;
  std::string progress = "auto";
  double progress_interval_s = 2.0;    // a person watching a log sees it move
  int compression = 1;                 // zlib level of the results file's datasets (0: none)
  double synthetic_run_cost_s = -1.0;  // bench only (hidden): runs sleep this long and simulate nothing
  EngineOptions engine;                // --max-batch, --flush-interval
};

// Rank 0's state between the checks and the end.
struct Rank0 {
  std::unique_ptr<results::LockFile> lock;         // the output's, for the whole session (first in, last out)
  std::unique_ptr<results::CampaignFile> file;  // the results file being written (a temporary name)
  std::unique_ptr<results::Journal> journal;
  std::unique_ptr<Progress> progress;
  std::unique_ptr<Collector> collector;
  RestoreSummary restored;
  // Nothing written: no results file (its temporary one removed), the journal as it was, the
  // output's lock let go.
  void drop() {
    collector.reset();
    journal.reset();
    file.reset();
    lock.reset();
  }
};

// What every rank knows of the session once rank 0 has prepared it.
struct SessionSetup {
  std::int64_t session = 0;
  std::string output, temporary;           // absolute paths
  std::uint32_t campaign_crc = 0;
  std::vector<std::int64_t> rank0_chunks;  // the chunks rank 0 restored and keeps
  results::StatsRanks stats;               // the ranks that merge the statistics (engine.hpp)
  std::string to_bytes() const;
  static SessionSetup from_bytes(std::string_view bytes);
};

// Rank 0: runs `step` and returns kExitOk, or, when it throws, prints the error once (an
// io::InputError as it is: kExitBadInput; any other exception as "error: ...": kExitIoError) and
// drops r0: nothing written.
int run_rank0_step(Rank0& r0, const std::function<void()>& step);

// Collective: rank 0's `s` on every rank (a wait that does not spin, engine.hpp's wait_idle).
void broadcast_string(MPI_Comm comm, std::string& s);

// Collective: rank 0's lock and checks of the output (lock_and_check_output), then every other
// rank's check that it sees the output's directory (its lock file, holding rank 0's PID and host):
// the ranks write their chunks and journals next to the output. Returns the exit status, the same
// on every rank (kExitOk, or kExitBadInput with the error printed once).
int check_output_all(MPI_Comm comm, const CommandOptions& o, const campaign::CampaignContext& ctx, Rank0& r0);

// Rank 0: the results file (a temporary name until the end), the journal (new, or restored into
// `owner` through `engine` on --resume) and the collector. Throws io::InputError for what the user
// must decide.
void prepare_output(const CommandOptions& o, const std::string& campaign_text, const campaign::CampaignContext& ctx,
                    methods::Method& method, Rank0& r0);

// Rank 0, after prepare_output: the journal restored into rank 0's chunks (`owner`, `engine`),
// and the session's setup.
SessionSetup restore_output(const CommandOptions& o, const std::string& campaign_text, Rank0& r0, ChunkOwner& owner,
                            Engine& engine);

}  // namespace truss::parallel
