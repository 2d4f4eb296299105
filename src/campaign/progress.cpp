#include "campaign/progress.hpp"

#include <unistd.h>

#include <fmt/format.h>

namespace truss::campaign {

namespace {
std::string format_duration(double s) {
  if (!(s >= 0.0) || s > 1e7) return "?";
  const auto t = static_cast<long>(s + 0.5);
  if (t < 60) return fmt::format("{} s", t);
  if (t < 3600) return fmt::format("{} min {:02} s", t / 60, t % 60);
  return fmt::format("{} h {:02} min", t / 3600, (t % 3600) / 60);
}
}  // namespace

Progress::Progress(std::int64_t total, std::int64_t restored, ProgressMode mode, double line_interval_s, std::FILE* out)
    : total_(total), restored_(restored), terminal_(mode == ProgressMode::terminal ||
                                                    (mode == ProgressMode::automatic && ::isatty(::fileno(out)))),
      enabled_(mode != ProgressMode::none), interval_s_(terminal_ ? 0.2 : line_interval_s), out_(out),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

void Progress::update(std::int64_t done, std::int64_t failed) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - last_).count() < interval_s_) return;
  last_ = now;
  print(done, failed, false);
}

void Progress::finish(std::int64_t done, std::int64_t failed) {
  if (enabled_) print(done, failed, true);
}

void Progress::print(std::int64_t done, std::int64_t failed, bool final) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0.0 ? static_cast<double>(done - restored_) / elapsed : 0.0;
  const double left = rate > 0.0 ? static_cast<double>(total_ - done) / rate : -1.0;
  std::string line = fmt::format("[truss-campaign] {}/{} runs ({:.1f} %), {} failed, {:.0f} runs/s, ", done, total_,
                                 total_ ? 100.0 * static_cast<double>(done) / static_cast<double>(total_) : 100.0, failed, rate);
  line += final ? fmt::format("done in {}", format_duration(elapsed)) : fmt::format("{} left", format_duration(left));
  if (restored_ > 0) line += fmt::format(" ({} restored from the journal)", restored_);
  if (terminal_) fmt::print(out_, "\r{:<110}{}", line, final ? "\n" : "");
  else fmt::print(out_, "{}\n", line);
  std::fflush(out_);
}

}  // namespace truss::campaign
