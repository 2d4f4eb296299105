#include "methods/method.hpp"

#include "util/bytes.hpp"

namespace truss::methods {

std::string RoundPlan::to_bytes() const {
  std::string b;
  b.reserve(3 * sizeof(std::int64_t) + sizeof(std::uint32_t) + state.size());
  append_bytes(b);
  return b;
}

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

void Method::write_results(const ResultsPlace&) const {}

std::optional<FailureEstimate> Method::calc_failure_estimate(double) const { return std::nullopt; }

}  // namespace truss::methods
