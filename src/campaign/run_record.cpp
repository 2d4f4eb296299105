#include "campaign/run_record.hpp"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "sim/simulate.hpp"

namespace truss::campaign {

static_assert(std::endian::native == std::endian::little, "records and journals are little-endian byte images");

namespace {

// Saltelli: one factor per dispersion, spanning all its dimensions (bays, frames).
SamplePlan make_plan(const CampaignOptions& c, const DimensionLayout& L) {
  if (c.ensemble.sampling != SamplingMethod::saltelli)
    return SamplePlan(c.ensemble.sampling, c.ensemble.n_runs, std::max(1, L.total), c.ensemble.master_seed);
  return SamplePlan(SamplingMethod::saltelli, c.ensemble.n_runs, L.total, c.ensemble.master_seed, L.count);
}

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T>
void put_array(std::string& out, const std::vector<T>& v) {
  put(out, static_cast<std::uint32_t>(v.size()));
  if (!v.empty()) out.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

struct Reader {
  std::string_view b;
  std::size_t at = 0;
  void need(std::size_t n) const {
    if (b.size() - at < n) throw std::runtime_error("record truncated");
  }
  template <class T>
  T get() {
    need(sizeof(T));
    T v;
    std::memcpy(&v, b.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  template <class T>
  std::vector<T> get_array(std::size_t expected) {
    const auto n = get<std::uint32_t>();
    if (n != expected) throw std::runtime_error(fmt::format("record has {} values where {} are expected", n, expected));
    need(n * sizeof(T));
    std::vector<T> v(n);
    if (n > 0) std::memcpy(v.data(), b.data() + at, n * sizeof(T));  // v.data() may be null for n = 0
    at += n * sizeof(T);
    return v;
  }
};

}  // namespace

RunSampler::RunSampler(const CampaignOptions& c) : layout_(calc_layout(c)), plan_(make_plan(c, layout_)) {
  if (const std::string e = plan_.validate(); !e.empty()) throw std::invalid_argument("sampling plan: " + e);
}

void RunSampler::calc_uniforms(std::int64_t run_index, double* u) const {
  if (layout_.total > 0) plan_.calc_uniforms(run_index, u);
}

OutputColumns OutputColumns::make(const DimensionLayout& layout) {
  OutputColumns c;
  sim::RunResult probe;
  for (const auto& f : io::run_result_fields()) {
    if (std::string_view(f.name) == "wall_time_s") continue;
    const io::FieldValue v = f.get(probe);
    if (std::holds_alternative<double>(v)) c.f64.push_back(&f);
    else if (std::holds_alternative<std::int64_t>(v)) c.i64.push_back(&f);
  }
  for (const auto& f : io::bay_result_fields())
    if (std::holds_alternative<double>(f.get(sim::BayResult{}))) c.bay.push_back(&f);
  c.n_bays_max = layout.n_bays_max;
  c.n_inputs = layout.total;
  return c;
}

void RunRecord::append_bytes(std::string& out) const {
  put(out, run_index);
  put(out, static_cast<std::int8_t>(status));
  put(out, rank);
  put(out, wall_time_s);
  put(out, static_cast<std::uint32_t>(message.size()));
  out.append(message);
  put_array(out, f64);
  put_array(out, i64);
  put_array(out, bays);
  put_array(out, inputs);
}

RunRecord RunRecord::from_bytes(std::string_view bytes, const OutputColumns& cols) {
  Reader r{bytes};
  RunRecord rec;
  rec.run_index = r.get<std::int64_t>();
  const auto s = r.get<std::int8_t>();
  if (s < 0 || s >= sim::kRunStatusCount) throw std::runtime_error(fmt::format("record has an unknown status {}", s));
  rec.status = static_cast<sim::RunStatus>(s);
  rec.rank = r.get<std::int32_t>();
  rec.wall_time_s = r.get<double>();
  const auto len = r.get<std::uint32_t>();
  r.need(len);
  rec.message.assign(bytes.data() + r.at, len);
  r.at += len;
  rec.f64 = r.get_array<double>(cols.f64.size());
  rec.i64 = r.get_array<std::int64_t>(cols.i64.size());
  rec.bays = r.get_array<double>(cols.bay.size() * static_cast<std::size_t>(cols.n_bays_max));
  rec.inputs = r.get_array<double>(static_cast<std::size_t>(cols.n_inputs));
  if (r.at != bytes.size()) throw std::runtime_error("record has trailing bytes");
  return rec;
}

namespace {
// The options are checked where they are used, before anything is built from them.
CampaignOptions checked(CampaignOptions c) {
  if (std::string e = c.validate(); !e.empty()) throw std::invalid_argument("campaign options: " + e);
  return c;
}
}  // namespace

CampaignContext::CampaignContext(CampaignOptions c)
    : options(checked(std::move(c))), sampler(options), columns(OutputColumns::make(sampler.layout())) {}

namespace {

RunInputs calc_inputs(const CampaignContext& ctx, std::int64_t run_index) {
  std::vector<double> u(static_cast<std::size_t>(ctx.sampler.layout().total));
  ctx.sampler.calc_uniforms(run_index, u.data());
  RunInputs in = calc_run_inputs(ctx.options, ctx.sampler.layout(), u.data());
  in.scene.run.max_wall_time_s = ctx.options.ensemble.max_run_wall_time_s;
  return in;
}

}  // namespace

RunRecord calc_run_record(const CampaignContext& ctx, std::int64_t run_index, int rank) {
  const OutputColumns& cols = ctx.columns;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  RunRecord rec;
  rec.run_index = run_index;
  rec.rank = rank;
  rec.f64.assign(cols.f64.size(), nan);
  rec.i64.assign(cols.i64.size(), 0);
  rec.bays.assign(cols.bay.size() * static_cast<std::size_t>(cols.n_bays_max), nan);
  rec.inputs.assign(static_cast<std::size_t>(cols.n_inputs), nan);
  sim::RunResult r;
  try {
    const RunInputs in = calc_inputs(ctx, run_index);
    for (std::size_t i = 0, k = 0; i < in.values.size(); ++i)
      for (double v : in.values[i]) rec.inputs[k++] = v;
    r = sim::simulate(in.scene, in.mast);
  } catch (const std::exception& e) {
    // A dispersed value the model cannot take (validation passed on the nominal scene only).
    r = sim::RunResult{};
    r.status = sim::RunStatus::invalid_input;
    r.message = fmt::format("run {}: {}", run_index, e.what());
  }
  rec.status = r.status;
  rec.message = r.message;
  rec.wall_time_s = r.wall_time_s;
  for (std::size_t i = 0; i < cols.f64.size(); ++i) rec.f64[i] = std::get<double>(cols.f64[i]->get(r));
  for (std::size_t i = 0; i < cols.i64.size(); ++i) rec.i64[i] = std::get<std::int64_t>(cols.i64[i]->get(r));
  const std::size_t nb = std::min(r.bays.size(), static_cast<std::size_t>(cols.n_bays_max));
  for (std::size_t f = 0; f < cols.bay.size(); ++f)
    for (std::size_t b = 0; b < nb; ++b)
      rec.bays[f * static_cast<std::size_t>(cols.n_bays_max) + b] = std::get<double>(cols.bay[f]->get(r.bays[b]));
  return rec;
}

sim::RunResult calc_run_with_history(const CampaignContext& ctx, std::int64_t run_index, double step_s) {
  RunInputs in = calc_inputs(ctx, run_index);
  in.scene.run.output_step_s = step_s;
  return sim::simulate(in.scene, in.mast);
}

}  // namespace truss::campaign
