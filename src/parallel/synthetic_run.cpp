#include "parallel/synthetic_run.hpp"

#include <chrono>
#include <ctime>

namespace truss::parallel {

namespace {

// splitmix64 of (run, column) to a double in [0, 1).
double pseudo_value(std::int64_t run, std::uint64_t column) {
  std::uint64_t z = static_cast<std::uint64_t>(run) * 0x9E3779B97F4A7C15ULL + column * 0xD1B54A32D192ED03ULL + 1;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

void sleep_for(double s) {
  if (!(s > 0.0)) return;
  struct timespec ts;
  ts.tv_sec = static_cast<time_t>(s);
  ts.tv_nsec = static_cast<long>((s - static_cast<double>(ts.tv_sec)) * 1e9);
  while (nanosleep(&ts, &ts) != 0) {
  }
}

}  // namespace

campaign::RunRecord synthetic_run_record(const campaign::CampaignContext& ctx, std::int64_t run_index, int rank,
                                         double cost_s) {
  const auto t0 = std::chrono::steady_clock::now();
  sleep_for(cost_s);
  const campaign::OutputColumns& cols = ctx.columns;
  campaign::RunRecord r;
  r.run_index = run_index;
  r.rank = rank;
  std::uint64_t col = 0;
  for (std::size_t k = 0; k < cols.f64.size(); ++k) r.f64.push_back(pseudo_value(run_index, col++));
  for (std::size_t k = 0; k < cols.i64.size(); ++k)
    r.i64.push_back(static_cast<std::int64_t>(1000.0 * pseudo_value(run_index, col++)));
  const std::size_t n_bays = cols.bay.size() * static_cast<std::size_t>(cols.n_bays_max);
  for (std::size_t k = 0; k < n_bays; ++k) r.bays.push_back(pseudo_value(run_index, col++));
  for (int k = 0; k < cols.n_inputs; ++k) r.inputs.push_back(pseudo_value(run_index, col++));
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace truss::parallel
