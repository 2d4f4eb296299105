#include "results/resources.hpp"

#include <sys/resource.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <fmt/format.h>

#include "results/journal.hpp"

namespace truss::results {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string human(double bytes) {
  if (!std::isfinite(bytes)) return "unlimited";
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB", "ZiB"};
  int u = 0;
  while (bytes >= 1024.0 && u < 7) { bytes /= 1024.0; ++u; }
  return fmt::format("{:.4g} {}", bytes, units[u]);  // 1020 KiB, not 1.02e+03
}
// The keys the user wrote that set calc_max_runs, with their values ("ensemble.stop.max_runs =
// 1000000", "ensemble.subset.n_per_level = 2000 (max_levels = 20: at most 36200 runs)").
std::string describe_max_runs(const campaign::CampaignOptions& c) {
  return c.ensemble.method.options().describe_max_runs(c);
}
}  // namespace

ResourceEstimate estimate_resources(const campaign::CampaignContext& ctx) {
  const double n = static_cast<double>(campaign::calc_max_runs(ctx.options));
  // One run's record (campaign/record.hpp) and its session column: a row of the file.
  const double row = static_cast<double>(ctx.record.fixed_bytes()) + 8.0;
  ResourceEstimate e;
  // Results stream to the file in chunks (result_store.hpp): rank 0 keeps per run only a done
  // byte, and at the end one column read back for the statistics with its sorted copy and the ok
  // mask (8 + 8 + 1 bytes); per-bay columns are read in groups of at most 64 MiB (one column when
  // that is larger: results/summary_h5.cpp). The chunks in flight and that group are a constant,
  // not a per-run cost.
  e.bytes_per_run = 1.0 + 17.0;
  e.memory_bytes = n * e.bytes_per_run;
  e.output_bytes = n * row;                                                   // /runs and /timing, uncompressed
  e.journal_bytes = n * (row + 4.0 + static_cast<double>(results::kFrameHeader));  // a frame per record
  return e;
}

double available_memory_bytes() {
  double avail = kInf;
  std::ifstream mi("/proc/meminfo");
  for (std::string line; std::getline(mi, line);)
    if (line.rfind("MemAvailable:", 0) == 0) {
      std::istringstream ss(line.substr(13));
      double kib = 0;
      if (ss >> kib) avail = kib * 1024.0;
    }
  std::ifstream cg("/sys/fs/cgroup/memory.max");
  std::string v;
  if (cg >> v && v != "max") {
    try { avail = std::min(avail, std::stod(v)); } catch (const std::exception&) {}
  }
  rlimit rl{};
  if (::getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
    avail = std::min(avail, static_cast<double>(rl.rlim_cur));
  return avail;
}

double free_disk_bytes(const std::string& dir) {
  struct statvfs st{};
  if (::statvfs(dir.c_str(), &st) != 0) return kInf;
  return static_cast<double>(st.f_bavail) * static_cast<double>(st.f_frsize);
}

std::string check_resources(const campaign::CampaignContext& ctx, const std::string& output_path,
                            double journal_on_disk_bytes) {
  const ResourceEstimate e = estimate_resources(ctx);
  const std::string n = describe_max_runs(ctx.options);
  const double mem = available_memory_bytes();
  if (e.memory_bytes > 0.8 * mem)
    return fmt::format("error: {}: rank 0 would need about {} in memory ({} bytes per run: run "
                       "flags, one column for the statistics), more than 80 % of the {} available; use fewer runs "
                       "(at most about {})",
                       n, human(e.memory_bytes), e.bytes_per_run, human(mem),
                       static_cast<std::int64_t>(std::floor(0.8 * mem / e.bytes_per_run)));
  const std::filesystem::path p(output_path);
  const std::string dir = p.has_parent_path() ? p.parent_path().string() : ".";
  const double disk = free_disk_bytes(dir);
  const double journal_to_write = std::max(0.0, e.journal_bytes - journal_on_disk_bytes);
  if (e.output_bytes + journal_to_write > disk)
    return fmt::format("error: {}: the results file (about {}) and the journal (about {}{}) need "
                       "more than the {} free in {}; free space or use fewer runs",
                       n, human(e.output_bytes), human(e.journal_bytes),
                       journal_on_disk_bytes > 0 ? fmt::format(", {} of it written", human(journal_on_disk_bytes)) : "",
                       human(disk), dir);
  // A file-size limit (ulimit -f) would stop the journal mid-campaign (EFBIG, exit 3): refuse now.
  rlimit fsize{};
  if (::getrlimit(RLIMIT_FSIZE, &fsize) == 0 && fsize.rlim_cur != RLIM_INFINITY &&
      e.journal_bytes > static_cast<double>(fsize.rlim_cur))
    return fmt::format("error: {}: the journal (about {}) would pass the file-size limit of this "
                       "process ({}, ulimit -f); raise the limit or use fewer runs",
                       n, human(e.journal_bytes), human(static_cast<double>(fsize.rlim_cur)));
  return {};
}

}  // namespace truss::results
