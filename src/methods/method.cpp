#include "methods/method.hpp"

#include "methods/fixed_design.hpp"
#include "methods/stop_method.hpp"
#include "methods/subset_method.hpp"
#include "methods/sweep_method.hpp"
#include "util/bytes.hpp"

namespace truss::methods {

std::string RoundPlan::to_bytes() const {
  std::string b;
  util::put(b, round);
  util::put(b, first_run);
  util::put(b, n_runs);
  util::put(b, static_cast<std::uint32_t>(state.size()));
  b += state;
  return b;
}

RoundPlan RoundPlan::from_bytes(std::string_view bytes) {
  util::ByteReader r(bytes, "a round plan");
  RoundPlan p;
  p.round = r.get<std::int64_t>();
  p.first_run = r.get<std::int64_t>();
  p.n_runs = r.get<std::int64_t>();
  p.state = r.get_bytes(r.get<std::uint32_t>());
  r.expect_end();
  return p;
}

void Method::write_results(hid_t, std::int64_t) const {}

std::unique_ptr<Method> make_method(const campaign::CampaignContext& ctx) {
  if (ctx.options.sweep.active) return std::make_unique<SweepMethod>(ctx);
  if (ctx.options.ensemble.method == campaign::EnsembleMethod::subset) return std::make_unique<SubsetMethod>(ctx);
  if (ctx.options.ensemble.stop) return std::make_unique<StopMethod>(ctx);
  if (ctx.options.ensemble.sampling == sampling::SamplingMethod::saltelli) return std::make_unique<Saltelli>(ctx);
  return std::make_unique<FixedDesign>(ctx);
}

}  // namespace truss::methods
