// Every rank's share of the results: the chunks it owns (chunk k: rank 1 + k mod (P - 1) on P > 1
// ranks, rank 0 on one rank and for the chunks it restored from the journals). The records of a
// chunk's runs come to its owner from whichever ranks computed them; the owner journals them (its
// part journal; rank 0's is its own journal), builds the chunk (results/chunk_builder.hpp), sends
// rank 0 each round part and each complete chunk's report, and writes the chunk's bytes into the
// results file where rank 0 placed them. Rank 0's work is per chunk; no rank handles every result.
//
// Messages to rank 0 go through `send` (MPI, or rank 0's own queue); the engine hands the owner
// what rank 0 answers. Before a round part leaves, the records it covers are written out to the
// journal, so that rank 0 journals the next round's plan only after the records of this one
// survive the process.
#pragma once
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "methods/method.hpp"
#include "results/chunk_builder.hpp"
#include "results/chunk_messages.hpp"
#include "results/chunk_stats.hpp"
#include "results/journal.hpp"

namespace truss::parallel {

// What a rank's owner writes into: the journal and the results file of this session.
struct OwnerFiles {
  int rank = 0;
  std::int64_t session = 0;
  std::string output;          // the results file (part journals next to it)
  std::string temporary;       // the results file being written (CampaignFile::temporary_path)
  std::uint32_t campaign_crc = 0;
  results::Journal* journal = nullptr;  // rank 0: its own journal; others: a part journal made at the first record
  results::StatsRanks stats;            // where the chunks' statistics summaries go (engine.hpp)
};

class ChunkOwner {
 public:
  using Send = std::function<void(int dest, int tag, std::string bytes)>;
  ChunkOwner(const campaign::RecordLayout& layout, const results::StoreOptions& opts, std::vector<std::size_t> observed,
             OwnerFiles files, Send send, double flush_interval_s);
  ~ChunkOwner();
  ChunkOwner(const ChunkOwner&) = delete;
  ChunkOwner& operator=(const ChunkOwner&) = delete;

  void add_round(const methods::RoundPlan& plan);
  void end_rounds();
  // A message of sealed run frames of chunks this rank owns, journaled and built. Frames of a
  // round not planned here yet wait for its plan. Throws std::runtime_error for a frame that is
  // not a record of its round.
  void add_records(std::string_view frames);
  // --resume: a record of a journal (not journaled again), stored by `session`.
  void replay_record(std::string_view record, std::int64_t session);
  void set_session(std::int64_t session) { files_.session = session; }
  void on_placement(std::string_view bytes);
  // The windows of a statistics rank's columns (`source`), or its ask for the first ones.
  void on_windows(int source, std::string_view bytes);
  void on_seed_ask(int source);
  // One unit of work (round parts and reports out, one dataset encoded, the journal's periodic
  // sync); false when there was none.
  bool step();
  // Rounds ended and every chunk it owns written: the results file synced and closed, the journal
  // synced (then rank 0 may commit).
  bool done() const;
  bool ended() const { return ended_; }  // end_rounds() called
  void finish();
  // SIGINT/SIGTERM: the journal's buffer written out (what it holds survives the process).
  void write_out_journal();
  std::vector<std::int64_t> open_chunks() const;  // chunks with rows in and not complete
  // Complete chunks waiting to be encoded: past kMaxBacklog the rank takes no more records until
  // it has caught up (Node::pause_records).
  bool behind() const { return to_encode_.size() + (encoding_ ? 1 : 0) > kMaxBacklog; }
  static constexpr std::size_t kMaxBacklog = 2;
  std::size_t peak_chunks() const { return builder_.peak_chunks(); }
  const campaign::RecordLayout& layout() const { return builder_.layout(); }
  std::size_t n_statistics_columns() const { return builder_.columns().n_stats; }
  std::int64_t n_chunks() const { return builder_.n_chunks(); }  // of the rounds planned so far

 private:
  void journal(std::string_view frames);
  bool send_parts();      // true if it sent any
  bool start_encoding();  // true if it started one or asked for the windows
  void write_chunk(const results::ChunkPlacement& p);

  results::ChunkBuilder builder_;
  OwnerFiles files_;
  Send send_;
  double flush_interval_s_;
  std::unique_ptr<results::Journal> part_;  // a rank other than 0: its part journal
  int data_fd_ = -1;                        // the results file, for the chunks' bytes
  std::vector<statistics::Windows> windows_;  // every statistics column's, each range from its rank
  int windows_missing_ = -1;                  // statistics ranks yet to send their first (-1: not asked)
  std::vector<std::string> waiting_;  // frames of rounds not planned here yet
  std::optional<std::int64_t> encoding_;                      // the chunk being encoded
  results::EncodedChunk encoded_;
  std::map<std::int64_t, results::EncodedChunk> placing_;     // reported, awaiting their placement
  std::deque<std::int64_t> to_encode_;
  bool ended_ = false;
  std::chrono::steady_clock::time_point last_sync_ = std::chrono::steady_clock::now();
};

}  // namespace truss::parallel
