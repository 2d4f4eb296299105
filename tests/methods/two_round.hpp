// A toy method with two rounds, written against methods/method.hpp alone (no change to the engine,
// the journal or the results file), to show that a method can choose its next points from the
// outputs of earlier runs:
//   round 0: ensemble.n_runs Monte Carlo runs;
//   round 1: if the 95 % confidence interval of the mean of `output` over round 0's ok runs,
//            +- 1.96 s / sqrt(n), is wider than rel_half_width |mean|, the runs that would bring it
//            there, n (h / (rel_half_width |mean|))^2 - n, between 1 and 3 n0; their points are
//            keyed by a digest of round 0's mean (the round's state), so they depend on round 0's
//            outputs and a resume that re-planned from other records would give other points;
//   round 2: done.
// Its options are its own (method_options.hpp), a row added to the built-in method table
// (two_round_row) with nothing else changed: ensemble.method = "two_round" and
//   [ensemble.two_round]  output = a float64 column of /runs (default "peak_drive_force_N"),
//                         rel_half_width = the target, positive (default 0.02).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "campaign/method_input.hpp"
#include "methods/method_table.hpp"
#include "sampling/sampling.hpp"
#include "util/bytes.hpp"

namespace truss::test {

struct TwoRoundOptions : campaign::MethodOptionsOf<TwoRoundOptions> {
  std::string output = "peak_drive_force_N";
  double rel_half_width = 0.02;

  std::string validate(const campaign::CampaignOptions&) const override {
    if (campaign::find_run_column_unit(output).empty())
      return fmt::format("ensemble.two_round.output: \"{}\" is not a float64 column of /runs", output);
    if (!(rel_half_width > 0.0 && std::isfinite(rel_half_width)))
      return fmt::format("ensemble.two_round.rel_half_width: must be positive and finite, got {}", rel_half_width);
    return {};
  }
  std::string to_toml() const override {
    return "[ensemble.two_round]\n" + campaign::write_options(table(), *this) + "\n";
  }
  // Round 0's n0 runs and at most 3 n0 in round 1.
  std::int64_t calc_max_runs(const campaign::CampaignOptions& c) const override { return 4 * c.ensemble.n_runs; }

  static const campaign::OptionTable<TwoRoundOptions>& table() {
    static const campaign::OptionTable<TwoRoundOptions> t{
        "ensemble.two_round", "a toy method of two rounds", {
            TRUSS_OPTION_TEXT(TwoRoundOptions, "output", output, "a float64 column of /runs"),
            TRUSS_OPTION_REAL(TwoRoundOptions, "rel_half_width", rel_half_width, "1", campaign::kAnyNumber,
                              "the target: the mean's 95 % half-width over |mean|"),
        }};
    return t;
  }
  static std::unique_ptr<campaign::MethodOptions> parse(const campaign::MethodInput& in) {
    auto o = std::make_unique<TwoRoundOptions>();
    campaign::read_method_table(in, table(), *o);
    return o;
  }
};

class TwoRound : public methods::Method {
 public:
  TwoRound(const campaign::CampaignContext& ctx, std::string output, double rel_half_width)
      : ctx_(ctx), output_(std::move(output)), rel_(rel_half_width) {}

  std::vector<std::string> observed_outputs() const override { return {output_}; }

  methods::Proposal propose(std::int64_t round, const methods::RoundRecords& previous) override {
    const std::int64_t n0 = ctx_.options.ensemble.n_runs;
    if (round == 0) return {n0, {}};
    if (round > 1) return {};
    double sum = 0.0, sum2 = 0.0;
    std::int64_t n = 0;
    const std::vector<double>& y = previous.outputs.at(0);
    for (std::size_t i = 0; i < y.size(); ++i)
      if (previous.status[i] == 0 && std::isfinite(y[i])) {
        sum += y[i];
        ++n;
      }
    if (n < 2) return {};
    const double mean = sum / static_cast<double>(n);
    for (std::size_t i = 0; i < y.size(); ++i)
      if (previous.status[i] == 0 && std::isfinite(y[i])) sum2 += (y[i] - mean) * (y[i] - mean);
    const double half = 1.96 * std::sqrt(sum2 / static_cast<double>(n - 1) / static_cast<double>(n));
    const double target = rel_ * std::abs(mean);
    if (half <= target) return {};
    const double wanted = static_cast<double>(n) * (half / target) * (half / target) - static_cast<double>(n);
    const auto more = static_cast<std::int64_t>(std::clamp(std::ceil(wanted), 1.0, 3.0 * static_cast<double>(n0)));
    std::uint64_t bits = 0;
    std::memcpy(&bits, &mean, sizeof bits);
    std::string state;
    util::put(state, sampling::mix64(bits));
    return {more, state};
  }

  void calc_uniforms(const methods::RoundPlan& plan, std::int64_t run, double* u) const override {
    std::uint64_t key = ctx_.options.ensemble.master_seed;
    if (plan.state.size() == 8) key ^= util::get_at<std::uint64_t>(plan.state.data());
    for (int j = 0; j < ctx_.dims.total; ++j) u[j] = sampling::counter_uniform(key, run, j);
  }

 private:
  const campaign::CampaignContext& ctx_;
  std::string output_;
  double rel_;
};

// The method's row: its name, its table and how it is made.
inline methods::MethodRow two_round_row() {
  return {{"two_round", {}, campaign::MethodSelection::by_name, &TwoRoundOptions::parse},
          [](const campaign::CampaignContext& ctx, const methods::MethodTable&) -> std::unique_ptr<methods::Method> {
            const auto& o = ctx.options.ensemble.method.as<TwoRoundOptions>();
            return std::make_unique<TwoRound>(ctx, o.output, o.rel_half_width);
          }};
}

}  // namespace truss::test
