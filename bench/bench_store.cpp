// Benchmark (not a test): rank 0's serial work per result and at the end, without MPI.
//   per-run cost c:     calc_run_record of the campaign's runs (what every rank does per run);
//   per-result cost h:  what rank 0 does with each result: journal append (with its CRC, which the
//                       campaign computes on the worker), ResultStore::add_bytes and the chunk
//                       writes: --compression 0; 1 encoded on rank 0 (one rank); 1 encoded by a
//                       second thread standing for the workers (only rank 0's thread is timed);
//   tail:               CampaignFile::finish: statistics from the columns read back, Sobol' indices,
//                       attributes, close, sync, rename.
// Times are thread CPU time (CLOCK_THREAD_CPUTIME_ID of the main thread, i.e. rank 0: a shared, loaded machine does not
// inflate them) and wall time; medians of REPEATS. The records are computed once and replayed
// (cycled over the first N_DISTINCT runs, run indices 0..N_RUNS-1) so that N_RUNS can be large.
// Usage: bench_store CAMPAIGN.toml N_RUNS [REPEATS] [N_DISTINCT] [DIR] [--set KEY=VALUE ...]
#include <malloc.h>
#include <time.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "campaign/campaign_h5.hpp"
#include "campaign/journal.hpp"
#include "campaign/result_store.hpp"
#include "campaign/run_record.hpp"

using namespace truss;

namespace {

double cpu_now() {  // this thread's CPU time: rank 0's own work, not the simulated worker's
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
double wall_now() { return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Times {
  double h_cpu, h_wall, tail_cpu, tail_wall;
};

// A worker rank that encodes chunks: a thread taking jobs from rank 0 and handing back their
// outputs (in the campaign they travel with batches and results over MPI).
class Encoder {
 public:
  Encoder() : t_([this] { loop(); }) {}
  ~Encoder() {
    {
      std::lock_guard<std::mutex> l(m_);
      stop_ = true;
    }
    cv_.notify_all();
    t_.join();
  }
  void put(std::string job) {
    {
      std::lock_guard<std::mutex> l(m_);
      in_.push_back(std::move(job));
      ++pending_;
    }
    cv_.notify_all();
  }
  // Rank 0: outputs that are ready (wait: until at most `keep` jobs are still being encoded). One
  // thread encodes about 7 times slower than rank 0 stores; in a campaign P - 1 workers encode and
  // results arrive at their pace, so rank 0 waits (without CPU) rather than encode the backlog.
  void collect(campaign::ResultStore& store, int keep) {
    std::unique_lock<std::mutex> l(m_);
    cv_.wait(l, [this, keep] { return pending_ <= keep; });
    std::deque<std::string> out;
    out.swap(out_);
    l.unlock();
    for (const auto& o : out) store.job_done(o);
  }

 private:
  void loop() {
    std::unique_lock<std::mutex> l(m_);
    for (;;) {
      cv_.wait(l, [this] { return stop_ || !in_.empty(); });
      if (in_.empty()) return;
      std::string job = std::move(in_.front());
      in_.pop_front();
      l.unlock();
      std::string out;
      campaign::encode_job_output(job, out);
      l.lock();
      out_.push_back(std::move(out));
      --pending_;
      cv_.notify_all();
    }
  }
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<std::string> in_, out_;
  int pending_ = 0;
  bool stop_ = false;
  std::thread t_;
};

// One replay of n results into a journal and a results file in dir; the files are removed after.
// offload: encoding jobs go to an Encoder thread (a worker rank), one taken per 32 results (a batch).
Times replay(const campaign::CampaignContext& ctx, const std::vector<std::string>& recs, std::int64_t n, int level,
             bool offload, const std::string& dir) {
  const std::string out = dir + "/bench_store.h5";
  std::filesystem::remove(out + ".journal");
  campaign::Journal journal = campaign::Journal::create(out + ".journal", "bench");
  campaign::CampaignFile file(out, ctx, campaign::StoreOptions{4096, level, offload});
  std::unique_ptr<Encoder> enc;
  if (offload) enc = std::make_unique<Encoder>();
  std::string bytes, job;
  const double c0 = cpu_now(), w0 = wall_now();
  for (std::int64_t i = 0; i < n; ++i) {
    bytes = recs[static_cast<std::size_t>(i) % recs.size()];
    std::memcpy(bytes.data(), &i, sizeof i);  // a record starts with its run index
    journal.append(campaign::FrameKind::run, bytes);
    file.store().add_bytes(bytes, 0);
    if (enc && i % 32 == 31) {
      if (file.store().take_job(job)) enc->put(std::move(job));
      enc->collect(file.store(), 2);
    }
  }
  if (enc) enc->collect(file.store(), 0);
  journal.flush();
  const double c1 = cpu_now(), w1 = wall_now();
  const std::int64_t offloaded = file.store().jobs_offloaded(), local = file.store().jobs_local();
  campaign::CampaignFileInfo info;
  file.finish({}, info, true);
  const double c2 = cpu_now(), w2 = wall_now();
  if (std::getenv("BENCH_PHASES"))
    std::fprintf(stderr, "level %d offload %d: %lld jobs offloaded, %lld local\n", level, offload ? 1 : 0,
                 static_cast<long long>(offloaded), static_cast<long long>(local));
  journal.close_and_remove();
  std::filesystem::remove(out);
  return {(c1 - c0) / static_cast<double>(n), (w1 - w0) / static_cast<double>(n), c2 - c1, w2 - w1};
}

}  // namespace

int main(int argc, char** argv) {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);  // as truss-campaign does (parallel/campaign_driver.cpp)
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_store CAMPAIGN.toml N_RUNS [REPEATS] [N_DISTINCT] [DIR] [--set KEY=VALUE ...]\n");
    return 2;
  }
  std::vector<std::string> sets;
  std::vector<std::string> pos;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--set" && i + 1 < argc) sets.emplace_back(argv[++i]);
    else pos.emplace_back(argv[i]);
  }
  const std::int64_t n = std::atoll(pos[1].c_str());
  const int repeats = pos.size() > 2 ? std::atoi(pos[2].c_str()) : 3;
  const std::int64_t distinct = std::min<std::int64_t>(n, pos.size() > 3 ? std::atoll(pos[3].c_str()) : 2000);
  const std::string dir = pos.size() > 4 ? pos[4] : ".";
  sets.push_back("ensemble.n_runs=" + std::to_string(n));
  const campaign::CampaignContext ctx(campaign::parse_campaign_file(pos[0], sets));
  std::vector<std::string> recs(static_cast<std::size_t>(distinct));
  const double c0 = cpu_now();
  for (std::int64_t i = 0; i < distinct; ++i) campaign::calc_run_record(ctx, i, 0).append_bytes(recs[static_cast<std::size_t>(i)]);
  const double c = (cpu_now() - c0) / static_cast<double>(distinct);
  std::printf("campaign %s, %lld runs (records of %zu bytes, %lld distinct), per-run cost c = %.1f us CPU\n", pos[0].c_str(),
              static_cast<long long>(n), recs[0].size(), static_cast<long long>(distinct), 1e6 * c);
  std::printf("| compression | encoding | h CPU (us) | h wall (us) | h / c | tail CPU (s) | tail wall (s) | tail CPU per 100k runs (s) |\n");
  std::printf("|---:|---|---:|---:|---:|---:|---:|---:|\n");
  for (auto [level, offload] : {std::pair{0, false}, std::pair{1, false}, std::pair{1, true}}) {
    std::vector<double> hc, hw, tc, tw;
    for (int r = 0; r < repeats; ++r) {
      const Times t = replay(ctx, recs, n, level, offload, dir);
      hc.push_back(t.h_cpu);
      hw.push_back(t.h_wall);
      tc.push_back(t.tail_cpu);
      tw.push_back(t.tail_wall);
    }
    std::printf("| %d | %s | %.2f | %.2f | %.2f %% | %.3f | %.3f | %.3f |\n", level,
                level == 0 ? "none" : offload ? "by a worker" : "rank 0", 1e6 * median(hc), 1e6 * median(hw),
                100.0 * median(hc) / c, median(tc), median(tw), median(tc) * 1e5 / static_cast<double>(n));
  }
  return 0;
}
