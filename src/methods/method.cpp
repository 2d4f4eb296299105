#include "methods/method.hpp"

#include "util/bytes.hpp"
#include "util/isal.hpp"

namespace truss::methods {

void RoundPlan::append_bytes(std::string& out) const {
  util::put(out, round);
  util::put(out, first_run);
  util::put(out, n_runs);
  util::put(out, static_cast<std::uint32_t>(state.size()));
  out += state;
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

PlanDigest PlanDigest::of(const RoundPlan& plan) {
  return {plan.round, plan.first_run, plan.n_runs, static_cast<std::uint32_t>(plan.state.size()),
          util::calc_crc32(plan.state)};
}

std::string PlanDigest::to_bytes() const {
  std::string b;
  util::put(b, round);
  util::put(b, first_run);
  util::put(b, n_runs);
  util::put(b, state_bytes);
  util::put(b, state_crc32);
  return b;
}

PlanDigest PlanDigest::from_bytes(std::string_view bytes) {
  util::ByteReader r(bytes, "a round plan's digest");
  PlanDigest d;
  d.round = r.get<std::int64_t>();
  d.first_run = r.get<std::int64_t>();
  d.n_runs = r.get<std::int64_t>();
  d.state_bytes = r.get<std::uint32_t>();
  d.state_crc32 = r.get<std::uint32_t>();
  r.expect_end();
  return d;
}

void Method::write_results(const ResultsPlace&) const {}

std::optional<FailureEstimate> Method::calc_failure_estimate(double) const { return std::nullopt; }

}  // namespace truss::methods
