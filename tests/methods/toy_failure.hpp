// A toy method with a [failure] event, written against the public headers alone (methods/method.hpp,
// campaign/method_input.hpp) with no change to the engine, the campaign's options or the sweep:
//   round 0: the first first_share of ensemble.n_runs Monte Carlo points; round 1: the rest; done.
// It estimates the probability of the campaign's [failure] event: the share of its runs that fail
// it, with its Clopper-Pearson interval (the shared FailureCount). Its options are a struct and its
// rows ([ensemble.toy] first_share, in (0, 1), default 0.5) and the [failure] table; its row, toy_row(),
// is all a campaign needs to run it, alone or, with a [sweep], at each design value.
#pragma once
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "campaign/method_input.hpp"
#include "io/h5_util.hpp"
#include "methods/failure_count.hpp"
#include "methods/method_table.hpp"
#include "sampling/sampling.hpp"

namespace truss::test {

struct ToyOptions : campaign::MethodOptionsOf<ToyOptions> {
  double first_share = 0.5;
  campaign::FailureOptions failure;

  std::string validate(const campaign::CampaignOptions&) const override {
    if (failure.kind == campaign::FailureKind::none) return "failure: the toy method needs a [failure] table";
    return campaign::check_option_ranges(table(), *this, "ensemble.toy.");
  }
  std::string to_toml() const override {
    return "[ensemble.toy]\n" + campaign::write_options(table(), *this) + "\n" + campaign::failure_toml(failure);
  }
  const campaign::FailureOptions* failure_event() const override { return &failure; }

  static const campaign::OptionTable<ToyOptions>& table() {
    static const campaign::OptionTable<ToyOptions> t{
        "ensemble.toy", "a toy method: Monte Carlo in two rounds, the share of failing runs", {
            TRUSS_OPTION_REAL(ToyOptions, "first_share", first_share, "1", campaign::open_range(0, 1),
                              "the first round's share of ensemble.n_runs"),
        }};
    return t;
  }
  static campaign::TableDoc table_doc() { return campaign::describe_options(table()); }
  static std::unique_ptr<campaign::MethodOptions> parse(const campaign::MethodInput& in) {
    auto o = std::make_unique<ToyOptions>();
    campaign::read_method_table(in, table(), *o);
    campaign::read_failure_event(in, o->failure);
    return o;
  }
};

class ToyFailure : public methods::Method {
 public:
  explicit ToyFailure(const campaign::CampaignContext& ctx)
      : ctx_(ctx), opt_(ctx.options.ensemble.method.as<ToyOptions>()), count_(opt_.failure) {}

  std::vector<std::string> observed_outputs() const override { return {opt_.failure.column}; }

  methods::Proposal propose(std::int64_t round, const methods::RoundRecords& previous) override {
    const std::int64_t n = ctx_.options.ensemble.n_runs;
    const auto first = std::clamp<std::int64_t>(std::llround(opt_.first_share * static_cast<double>(n)), 1, n);
    if (round > 0) count_.add(previous);
    if (round == 0) return {first, {}};
    if (round == 1 && n > first) return {n - first, {}};
    return {};
  }

  void calc_uniforms(const methods::RoundPlan&, std::int64_t run, double* u) const override {
    for (int j = 0; j < ctx_.dims.total; ++j) u[j] = sampling::counter_uniform(ctx_.options.ensemble.master_seed, run, j);
  }

  std::optional<methods::FailureEstimate> calc_failure_estimate(double confidence) const override {
    return count_.calc_binomial_estimate(confidence);
  }

  void write_results(const methods::ResultsPlace& place) const override {
    io::h5::Handle g = io::h5::create_group(place.group, "toy");
    io::h5::write_scalar(g.get(), "runs", "1", count_.runs());
    io::h5::write_scalar(g.get(), "failures", "1", count_.failures());
  }

 private:
  const campaign::CampaignContext& ctx_;
  const ToyOptions& opt_;
  methods::FailureCount count_;
};

// The method's row: its name, the root table it reads, its options and how it is made.
inline methods::MethodRow toy_row() {
  return {{"toy", {"failure"}, campaign::MethodSelection::by_name, &ToyOptions::parse, &ToyOptions::table_doc},
          &methods::make_method_of<ToyFailure>};
}

}  // namespace truss::test
