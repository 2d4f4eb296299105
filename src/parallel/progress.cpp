#include "parallel/progress.hpp"

#include <unistd.h>

#include <fmt/format.h>

#include <cmath>
#include <utility>

namespace truss::parallel {

namespace {
std::string format_duration(double s) {
  if (!(s >= 0.0) || s > 1e7) return "?";
  const auto t = static_cast<long>(s + 0.5);
  if (t < 60) return fmt::format("{} s", t);
  if (t < 3600) return fmt::format("{} min {:02} s", t / 60, t % 60);
  return fmt::format("{} h {:02} min", t / 3600, (t % 3600) / 60);
}
}  // namespace

std::string format_status_counts(const StatusCounts& counts) {
  std::string s;
  for (int k = 0; k < sim::kRunStatusCount; ++k) {
    if (counts[static_cast<std::size_t>(k)] == 0) continue;
    if (!s.empty()) s += ", ";
    s += fmt::format("{} {}", counts[static_cast<std::size_t>(k)], sim::to_string(static_cast<sim::RunStatus>(k)));
  }
  return s.empty() ? "none yet" : s;
}

Progress::Progress(std::int64_t total, std::int64_t restored, ProgressMode mode, double line_interval_s, std::FILE* out)
    : total_(total), restored_(restored), terminal_(mode == ProgressMode::terminal ||
                                                    (mode == ProgressMode::automatic && ::isatty(::fileno(out)))),
      enabled_(mode != ProgressMode::none), interval_s_(terminal_ ? 0.2 : line_interval_s), out_(out),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::banner(const std::string& campaign, int ranks, const std::string& output) {
  if (!enabled_) return;
  fmt::print(out_, "[truss-campaign] campaign \"{}\": {} runs on {} rank{} -> {}{}\n", campaign, total_, ranks,
             ranks > 1 ? "s" : "", output, restored_ ? fmt::format(" ({} restored from the journal)", restored_) : "");
  std::fflush(out_);
}

bool Progress::due() {
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_).count() < interval_s_) return false;
  last_ = now;
  return true;
}

void Progress::finish(std::int64_t done, const StatusCounts& counts) {
  if (enabled_) print(done, counts, true);
}

void Progress::print(std::int64_t done, const StatusCounts& counts, bool final) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0.0 ? static_cast<double>(done - restored_) / elapsed : 0.0;
  if (!stage_.empty() && cap_ > 0 && !final) {
    const double most = rate > 0.0 ? static_cast<double>(cap_ - done) / rate : -1.0;
    const std::string line =
        fmt::format("[truss-campaign] {}: {} runs so far of at most {}: {}; {:.0f} runs/s, at most {} left", stage_,
                    done, cap_, format_status_counts(counts), rate, format_duration(most));
    if (terminal_) fmt::print(out_, "\r\033[K{}", line);
    else fmt::print(out_, "{}\n", line);
    std::fflush(out_);
    return;
  }
  const double left = rate > 0.0 ? static_cast<double>(total_ - done) / rate : -1.0;
  std::string line = fmt::format("[truss-campaign] {}/{} runs ({:.1f} %): {}; {:.0f} runs/s, ", done, total_,
                                 total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0,
                                 format_status_counts(counts), rate);
  line += final ? fmt::format("done in {}", format_duration(elapsed)) : fmt::format("{} left", format_duration(left));
  if (terminal_) fmt::print(out_, "\r\033[K{}{}", line, final ? "\n" : "");  // erase to the end of the line
  else fmt::print(out_, "{}\n", line);
  std::fflush(out_);
}

namespace {
// A readable unit for values up to |magnitude|: the largest prefix not above it (mN m, uJ, ...).
std::pair<std::string, double> readable_unit(const std::string& units, double magnitude) {
  static const std::vector<std::pair<std::string, std::vector<std::pair<const char*, double>>>> prefixes = {
      {"N", {{"mN", 1e-3}, {"N", 1.0}}},
      {"Nm", {{"uN m", 1e-6}, {"mN m", 1e-3}, {"N m", 1.0}}},
      {"J", {{"uJ", 1e-6}, {"mJ", 1e-3}, {"J", 1.0}}},
      {"Ns", {{"mN s", 1e-3}, {"N s", 1.0}}}};
  for (const auto& [u, opts] : prefixes) {
    if (u != units) continue;
    std::pair<std::string, double> best{opts.front().first, opts.front().second};
    for (const auto& [label, f] : opts)
      if (std::abs(magnitude) >= f) best = {label, f};
    return best;
  }
  return {units, 1.0};
}
}  // namespace

std::int64_t calc_runs_needed_p99_865() {
  const double p = 0.99865, confidence = 0.95;
  auto n = static_cast<std::int64_t>(std::floor(std::log(1.0 - confidence) / std::log(p)));
  while (1.0 - std::pow(p, static_cast<double>(n)) < confidence) ++n;  // exact at the boundary
  return n;
}

void print_design_summary(std::FILE* out, const std::vector<results::DesignValue>& values) {
  const std::int64_t needed = calc_runs_needed_p99_865();
  fmt::print(out, "[truss-campaign] design values (ok runs; nominal = base scene without dispersions):\n");
  for (const auto& v : values) {
    const auto [u, f] = readable_unit(v.units, std::isfinite(v.max) ? v.max : v.nominal);
    const std::string few = v.count >= needed ? ""
                            : fmt::format("  <- from {} ok run{}: too few for a P99.865 (its 95 % bound needs {})",
                                          v.count, v.count == 1 ? "" : "s", needed);
    fmt::print(out, "[truss-campaign]   {:<22} nominal {:>8.5g} {:<4}  P99.865 {:>8.5g} {:<4}  max {:>8.5g} {}{}\n",
               v.label, v.nominal / f, u, v.p99_865 / f, u, v.max / f, u, few);
  }
  std::fflush(out);
}

bool print_campaign_verdict(std::FILE* out, const StatusCounts& counts, const std::string& example) {
  std::int64_t total = 0;
  for (std::int64_t k : counts) total += k;
  const std::int64_t invalid = counts[static_cast<std::size_t>(sim::RunStatus::invalid_input)];
  if (invalid == 0) return true;
  const bool most = 2 * invalid > total;
  fmt::print(out,
             "[truss-campaign] {}: {} of {} runs are invalid input: the dispersions give scenes the model refuses{}\n",
             most ? "error" : "warning", invalid, total,
             most ? "; the results file is written, but its statistics stand on the few other runs" : "");
  if (!example.empty()) fmt::print(out, "[truss-campaign]   e.g. {}\n", example);
  if (most)
    fmt::print(out, "[truss-campaign]   check the [[dispersion]] entries (apply = \"relative\" takes a fraction: std = "
                    "0.05 is 5 %) and run again\n");
  std::fflush(out);
  return !most;
}

}  // namespace truss::parallel
