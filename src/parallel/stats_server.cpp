// A statistics rank's side of the engine (engine_detail.hpp, StatsServer).
#include "parallel/engine_detail.hpp"
#include "results/chunk_messages.hpp"

namespace truss::parallel::detail {

void StatsServer::send_windows(int dest) {
  results::ChunkPlacement p;
  p.index = -1;
  p.windows = stats_.windows();
  node_.send(dest, kTagWindows, results::to_bytes(p));
}

void StatsServer::handle(int tag, int source, std::string& bytes) {
  const double cpu0 = thread_cpu_s();
  if (tag == kTagSummary) {
    results::read_chunk_report(bytes, summary_);
    stats_.merge(summary_.index, summary_.summaries);
    send_windows(source);
  } else if (tag == kTagAskWindows) {
    if (stats_.seeded()) {
      send_windows(source);
    } else {
      want_windows_.push_back(source);
      if (!asked_seed_) node_.send(source, kTagAskSeed, {});
      asked_seed_ = true;
    }
  } else if (tag == kTagSeed) {
    stats_.seed(results::read_chunk_placement(bytes).windows);
    for (int w : want_windows_) send_windows(w);
    want_windows_.clear();
  }
  merge_cpu_s_ += thread_cpu_s() - cpu0;
}

bool StatsServer::send_if_complete(std::int64_t n_chunks) {
  if (sent_ || stats_.merged() != n_chunks) return false;
  results::StatsPart part = stats_.calc_part(n_chunks);
  part.merge_cpu_s = merge_cpu_s_;
  node_.send(0, kTagStats, results::to_bytes(part));
  sent_ = true;
  return true;
}

}  // namespace truss::parallel::detail
