// Benchmarks only: a campaign's result path on one process, without MPI: a record's frame into a
// journal, its row into its chunk (results/chunk_builder.hpp), each complete chunk encoded one
// dataset at a time (step(), between runs, as an owner does), placed by rank 0's store and its
// bytes written where the store placed them. The owner's part and the central part (rank 0's
// placement, the statistics rank's merge) are timed apart in thread CPU time.
#pragma once
#include <fcntl.h>
#include <time.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "results/campaign_file.hpp"
#include "results/chunk_stats.hpp"
#include "results/journal.hpp"

namespace truss::bench {

inline double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

class LocalResults {
 public:
  LocalResults(const std::string& out, const campaign::CampaignContext& ctx, std::int64_t n, int level)
      : out_(out), ctx_(ctx), stats_(ctx.record) {
    std::filesystem::remove(out + ".journal");
    journal_ = std::make_unique<results::Journal>(results::Journal::create(out + ".journal", "bench"));
    const results::StoreOptions opts{results::find_chunk_runs(n), level};
    file_ = std::make_unique<results::CampaignFile>(out, ctx, opts);
    file_->store().extend(n);
    builder_ = std::make_unique<results::ChunkBuilder>(ctx.record, opts, std::vector<std::size_t>{});
    builder_->add_round(0, 0, n);
    fd_ = ::open(file_->temporary_path().c_str(), O_WRONLY);
    if (fd_ < 0) std::abort();
  }
  ~LocalResults() {
    if (fd_ >= 0) ::close(fd_);
  }
  // The owner's part of a run's record: checked, journaled, into its chunk.
  void add(std::string_view frame) {
    const results::Frame f = results::read_frame(frame);
    if (f.kind != results::FrameKind::run || !ctx_.record.check(f.payload).empty()) std::abort();
    journal_->append_frame(frame);
    builder_->add(campaign::RecordView(f.payload, ctx_.record), 0);
    while (builder_->pop_part()) {
    }
  }
  // One dataset of a complete chunk encoded (the owner), or a chunk placed (rank 0) and written.
  bool step() {
    if (!encoding_) {
      const auto k = builder_->pop_complete();
      if (!k) return false;
      const double c0 = thread_cpu_s();
      if (!stats_.seeded()) stats_.seed(builder_->first_windows(*k));
      rank0_cpu_s += thread_cpu_s() - c0;
      encoding_ = *k;
      encoded_ = {};
    }
    if (!builder_->encode_step(*encoding_, stats_.windows(), encoded_)) return true;
    const double c0 = thread_cpu_s();
    const std::vector<results::ChunkAddress> at = file_->store().place(encoded_.report);
    stats_.merge(encoded_.report.index, encoded_.report.summaries);
    rank0_cpu_s += thread_cpu_s() - c0;
    for (std::size_t d = 0; d < at.size(); ++d)
      if (::pwrite(fd_, encoded_.bytes[d].data(), encoded_.bytes[d].size(), static_cast<off_t>(at[d].offset)) !=
          static_cast<ssize_t>(encoded_.bytes[d].size()))
        std::abort();
    encoding_.reset();
    return true;
  }
  // The last chunk, /stats, the file committed; the files removed.
  void finish() {
    builder_->end_rounds();
    while (step()) {
    }
    journal_->flush();
    file_->write_summary(stats_.calc_stats(builder_->n_chunks()), {}, sim::RunResult{}, results::CampaignFileInfo{});
    file_->commit(true);
    journal_->close_and_remove();
    std::filesystem::remove(out_);
  }
  double rank0_cpu_s = 0.0;  // rank 0's part and the statistics rank's (placement, statistics), thread CPU

 private:
  std::string out_;
  const campaign::CampaignContext& ctx_;
  std::unique_ptr<results::Journal> journal_;
  std::unique_ptr<results::CampaignFile> file_;
  std::unique_ptr<results::ChunkBuilder> builder_;
  results::ChunkStats stats_;
  std::optional<std::int64_t> encoding_;
  results::EncodedChunk encoded_;
  int fd_ = -1;
};

}  // namespace truss::bench
