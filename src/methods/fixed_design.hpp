// The one-shot methods: a design fixed before the first run (sampling/sampling.hpp's SamplePlan
// over the campaign's dimensions), n_runs runs in one round. Monte Carlo, Latin hypercube and
// Sobol' are FixedDesign; Saltelli adds the Sobol' indices of its design to the results file.
#pragma once
#include <optional>

#include "campaign/failure.hpp"
#include "methods/failure_count.hpp"
#include "methods/method.hpp"
#include "sampling/sampling.hpp"

namespace truss::methods {

class MethodTable;

// ensemble.method = "design": its points are ensemble.sampling's over ensemble.n_runs; no table of
// its own ([ensemble.design] takes no key). With a [failure] event, Monte Carlo runs estimate its
// probability (the share of failing runs): /failure, and a design sweep's value.
struct DesignOptions : campaign::MethodOptionsOf<DesignOptions> {
  campaign::FailureOptions failure;  // [failure]: the event whose probability it estimates (none: no estimate)
  // The design's rules (validate_sampling); with a [failure] event, Monte Carlo points.
  std::string validate(const campaign::CampaignOptions& c) const override;
  std::string to_toml() const override { return campaign::failure_toml(failure); }
  const campaign::FailureOptions* failure_event() const override { return &failure; }
  static std::unique_ptr<campaign::MethodOptions> parse(const campaign::MethodInput& in);
};

// The design's method: Saltelli for ensemble.sampling = "saltelli", else FixedDesign.
std::unique_ptr<Method> make_fixed_design(const campaign::CampaignContext& ctx, const MethodTable&);

class FixedDesign : public Method {
 public:
  // The campaign's SamplePlan: ensemble.sampling over every dimension; saltelli: one factor per
  // dispersion, spanning all its dimensions (bays, frames), so AB_g takes every dimension of
  // dispersion g from B; its base points are shifted Sobol' points of dimension 2d up to
  // 2d = kSaltelliSobolMaxDims, Monte Carlo points beyond. The campaign's validate() has checked
  // the plan (SamplePlan::validate).
  explicit FixedDesign(const campaign::CampaignContext& ctx);
  std::vector<std::string> observed_outputs() const override;
  Proposal propose(std::int64_t round, const RoundRecords& previous) override;
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  // With a [failure] event: /failure (its runs, failing runs, p and the nearest margin) and its line.
  void write_results(const ResultsPlace& place) const override;
  std::string calc_result_text() const override;
  std::optional<FailureEstimate> calc_failure_estimate(double confidence) const override;

 protected:
  const campaign::CampaignContext& ctx_;
  sampling::SamplePlan plan_;
  std::optional<FailureCount> failures_;  // with a [failure] event
};

// Sensitivity of one output: Sobol' indices per dispersion from a Saltelli design.
struct OutputSensitivity {
  std::string output;
  sampling::SobolIndices indices;
  std::int64_t n_blocks = 0, n_blocks_dropped = 0;
};

class Saltelli : public FixedDesign {
 public:
  using FixedDesign::FixedDesign;
  // /sensitivity: the indices of the peak loads and the deployment time (docs/hdf5-schema.md).
  void write_results(const ResultsPlace& place) const override;
  // The outputs whose sensitivity is computed.
  static const std::vector<std::string>& outputs();
  // Blocks with a failed run or a non-finite output are left out; fewer than 2 usable blocks give
  // NaN indices. `y`: the output of every run, `status` their statuses.
  OutputSensitivity calc_sensitivity(const std::string& output, const std::vector<std::int8_t>& status,
                                     const std::vector<double>& y) const;
};

}  // namespace truss::methods
