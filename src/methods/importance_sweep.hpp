// A design sweep whose inner method is "importance" ([sweep] with ensemble.method = "importance"),
// over a variable that changes only a distribution: a dispersion's spread, or the nominal of a key
// dispersed with apply = "offset" or "relative". One set of runs serves every value by likelihood
// ratios (sampling/reweighting.hpp):
//   runs      one cross-entropy importance sampling campaign (importance_method.hpp) of the base
//             value b's campaign (calc_campaign_at(c, b); b the widest spread, or the middle nominal),
//             its density adapted to the mixture of the values' laws, f_mix = (1/K) sum_k f_k: the
//             adaptation's ratio ln f_mix / f_b of a run's swept draws. Every run carries value b.
//             A spread sweep's final runs are drawn from the mixture of the values' laws carried to
//             the adapted mean (law_mixture.hpp), so each value's weights are those of a density of
//             its own spread; a nominal sweep's from N(mu, I).
//   estimate  value k's: the final runs' ln w = ln phi / h + sum_j [ln f_k(d_j) - ln f_b(d_j)], d_j the
//             swept dispersion's draws of the run (all its dimensions), by calc_weighted_estimate:
//             its p, CoV, interval, ESS and Pareto k, refused (the reason said, the value untrusted
//             so no allowable rests on it) where the weights degenerate, or where the density's mean
//             is too noisy (CrossEntropySampler::find_refusal).
//   verdict   the sweep's own (sweep_method.hpp: calc_sweep_verdict), /sweep as a sweep writes it;
//             the shared runs' adaptation and each value's ESS and Pareto k under /sweep/importance.
// A sweep that changes more than a distribution (a key not dispersed, apply = "absolute", a
// discrete law, a support that grows) is refused at validation (validate_reweighted_sweep), and so
// is refine: every listed value costs no run, so list the values wanted.
#pragma once
#include <memory>

#include "methods/importance_method.hpp"
#include "sampling/law_mixture.hpp"
#include "methods/sweep_method.hpp"

namespace truss::methods {

// The swept draws' laws: the base value b and the swept dispersion's block of dimensions, its law
// at b and at each listed value (in the draw's coordinate of the base, reweighting.hpp: DrawLaw).
struct SweepLaws {
  std::size_t base = 0;  // b
  sampling::SweptBlock block;
  bool spread = false;   // the values change a spread: the final density is their mixture
};

// The laws of a sweep's values, or why the sweep cannot be reweighted ("sweep.<field>: reason").
std::string find_sweep_laws(const campaign::CampaignOptions& c, const SweepOptions& opt, SweepLaws& laws);
// "" when a sweep with inner method "importance" can run: its variable changes only a distribution.
std::string validate_reweighted_sweep(const campaign::CampaignOptions& c, const SweepOptions& opt);

class ImportanceSweepMethod : public Method {
 public:
  explicit ImportanceSweepMethod(const campaign::CampaignContext& ctx);
  std::vector<std::string> observed_outputs() const override { return method_->observed_outputs(); }
  Proposal propose(std::int64_t round, const RoundRecords& previous) override {
    return method_->propose(round, previous);
  }
  void calc_uniforms(const RoundPlan& plan, std::int64_t run, double* u) const override;
  void write_results(const ResultsPlace& place) const override;
  bool runs_are_draws() const override { return false; }
  std::string calc_result_text() const override;
  std::string progress_stage() const override { return method_->progress_stage(); }
  std::int64_t run_cap() const override { return method_->run_cap(); }
  std::string calc_not_assessed() const override;
  // Each listed value's estimate, ascending (the sweep's values), from the shared runs.
  std::vector<SweepMethod::ValueResult> calc_value_results() const;
  std::vector<sampling::WeightedEstimate> calc_weighted_estimates() const;

 private:
  const campaign::CampaignContext& ctx_;
  const SweepOptions& opt_;
  SweepLaws laws_;
  std::unique_ptr<sampling::LawMixture> mixture_;  // the final density's deviation (spread sweeps)
  std::unique_ptr<campaign::CampaignContext> base_ctx_;
  std::unique_ptr<ImportanceMethod> method_;
  int dims_ = 0;
};

}  // namespace truss::methods
