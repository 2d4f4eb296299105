#include "campaign/evaluate.hpp"

#include <limits>

#include <fmt/format.h>

#include "sim/scene.hpp"
#include "sim/simulate.hpp"

namespace truss::campaign {

CampaignContext::CampaignContext(CampaignOptions c)
    : options(std::move(c)), dims(calc_layout(options)), record(options, dims) {}

namespace {

RunInputs calc_inputs(const CampaignContext& ctx, const double* u) {
  RunInputs in = calc_run_inputs(ctx.options, ctx.dims, u);
  in.scene.run.max_wall_time_s = ctx.options.ensemble.max_run_wall_time_s;
  return in;
}

}  // namespace

void append_run_record(const CampaignContext& ctx, const double* u, const RecordHead& head, std::string& out) {
  std::vector<double> inputs(static_cast<std::size_t>(ctx.dims.total), std::numeric_limits<double>::quiet_NaN());
  sim::RunResult r;
  try {
    const RunInputs in = calc_inputs(ctx, u);
    std::size_t k = 0;
    for (const auto& values : in.values)
      for (double v : values) inputs[k++] = v;
    r = sim::simulate(in.scene, in.mast);
  } catch (const std::exception& e) {
    // A dispersed value the model cannot take (validation passed on the nominal scene only).
    r = sim::RunResult{};
    r.status = sim::RunStatus::invalid_input;
    r.message = fmt::format("run {}: {}", head.run, e.what());
  }
  append_record(ctx.record, head, r, inputs, out);
}

sim::RunResult calc_run_with_history(const CampaignContext& ctx, const double* u, double step_s) {
  RunInputs in = calc_inputs(ctx, u);
  in.scene.run.output_step_s = step_s;
  return sim::simulate(in.scene, in.mast);
}

sim::RunResult calc_nominal_run(const CampaignOptions& c, double step_s) {
  sim::SceneOptions scene = c.base;
  scene.run.max_wall_time_s = c.ensemble.max_run_wall_time_s;
  scene.run.output_step_s = step_s;
  try {
    return sim::simulate(scene, sim::build_mast(scene));
  } catch (const std::exception& e) {
    sim::RunResult r;
    r.status = sim::RunStatus::invalid_input;
    r.message = fmt::format("nominal run: {}", e.what());
    return r;
  }
}

}  // namespace truss::campaign
