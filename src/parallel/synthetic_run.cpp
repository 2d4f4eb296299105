#include "parallel/synthetic_run.hpp"

#include <chrono>
#include <ctime>
#include <limits>

#include "campaign/failure.hpp"
#include "sampling/sampling.hpp"

namespace truss::parallel {

namespace {

// A double in [0, 1) from (run, column): SplitMix64's finaliser of both.
double pseudo_value(std::int64_t run, std::uint64_t column) {
  return static_cast<double>(sampling::mix64(static_cast<std::uint64_t>(run) * sampling::kGoldenGamma +
                                             column * 0xD1B54A32D192ED03ULL + 1) >> 11) * 0x1.0p-53;
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

void append_synthetic_record(const campaign::CampaignContext& ctx, const double* u, const campaign::RecordHead& head,
                             double cost_s, std::string& out) {
  const auto t0 = std::chrono::steady_clock::now();
  sleep_for(cost_s);
  std::vector<double> inputs;
  double limit_state = 0.0;  // the sum of each dispersion's first applied value
  try {
    const campaign::RunInputs in = campaign::calc_run_inputs(ctx.options, ctx.dims, u);
    for (const auto& values : in.values) inputs.insert(inputs.end(), values.begin(), values.end());
    for (std::size_t i = 0; i < ctx.options.dispersions.size(); ++i) limit_state += in.values[i].front();
  } catch (const std::exception&) {
    inputs.assign(static_cast<std::size_t>(ctx.dims.total), std::numeric_limits<double>::quiet_NaN());
    limit_state = std::numeric_limits<double>::quiet_NaN();
  }
  const campaign::FailureOptions* failure = ctx.options.ensemble.method.options().failure_event();
  const std::string failure_column = failure ? failure->column : std::string();
  const campaign::RecordLayout& L = ctx.record;
  campaign::RecordWriter w(L, out);
  w.set_i64(campaign::RecordLayout::kRun, head.run);
  w.set_i64(campaign::RecordLayout::kRound, head.round);
  w.set_i64(campaign::RecordLayout::kRank, head.rank);
  std::uint64_t column = 0;
  std::size_t k = 0;
  for (std::size_t f = campaign::RecordLayout::kWallTime + 1; f < L.fields().size(); ++f) {
    const campaign::Field& fd = L.fields()[f];
    for (int j = 0; j < fd.width; ++j) {
      if (fd.dispersion >= 0) {
        w.set_f64(f, inputs[k++], j);
      } else if (fd.run && fd.name == failure_column) {
        w.set_f64(f, limit_state, j);
        ++column;
      } else if (fd.type == campaign::ValueType::i64) {
        w.set_i64(f, static_cast<std::int64_t>(1000.0 * pseudo_value(head.run, column++)), j);
      } else {
        w.set_f64(f, pseudo_value(head.run, column++), j);
      }
    }
  }
  w.set_f64(campaign::RecordLayout::kWallTime,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  w.finish({});
}

}  // namespace truss::parallel
