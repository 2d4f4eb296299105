#include "methods/method.hpp"

#include "util/bytes.hpp"
#include "util/isal.hpp"

namespace truss::methods {

namespace {

// The head of a plan and of its digest: i64 round, i64 first_run, i64 n_runs.
template <class Plan>
void put_runs(std::string& out, const Plan& p) {
  util::put(out, p.round);
  util::put(out, p.first_run);
  util::put(out, p.n_runs);
}

template <class Plan>
void get_runs(util::ByteReader& r, Plan& p) {
  p.round = r.get<std::int64_t>();
  p.first_run = r.get<std::int64_t>();
  p.n_runs = r.get<std::int64_t>();
}

}  // namespace

void RoundPlan::append_bytes(std::string& out) const {
  put_runs(out, *this);
  util::put(out, static_cast<std::uint32_t>(state.size()));
  out += state;
}

RoundPlan RoundPlan::from_bytes(std::string_view bytes) {
  util::ByteReader r(bytes, "a round plan");
  RoundPlan p;
  get_runs(r, p);
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
  put_runs(b, *this);
  util::put(b, state_bytes);
  util::put(b, state_crc32);
  return b;
}

PlanDigest PlanDigest::from_bytes(std::string_view bytes) {
  util::ByteReader r(bytes, "a round plan's digest");
  PlanDigest d;
  get_runs(r, d);
  d.state_bytes = r.get<std::uint32_t>();
  d.state_crc32 = r.get<std::uint32_t>();
  r.expect_end();
  return d;
}

void Method::write_results(const ResultsPlace&) const {}

std::optional<FailureEstimate> Method::calc_failure_estimate(double) const { return std::nullopt; }

}  // namespace truss::methods
