// bench_sweep_fit — a design sweep's allowable on an analytic limit state, three ways, over many
// seeds: p(x) = Phi(-x) (the linear case of tests/numeric/subset_cases.hpp with beta = x, in 10
// standard normal dimensions), values x = 4 to 5.25 in steps of 0.25, target 1e-6 (true crossing
// x* = 4.7534; p falls as x grows: the allowable is a least value). Each value's p by subset
// simulation with its own seed, as a sweep runs it:
//   walk, MM             modified Metropolis, cov_bound, the walk on the declared side
//                        (find_allowable_on_side);
//   walk, aCS            adaptive conditional sampling, cov_interval, the walk on the declared side;
//   monotone fit         the same estimates through the isotonic fit (calc_monotone_fit), values the
//                        trust rule flags left out.
// Prints per way: sweeps without an allowable, allowables on the unsafe side of x* (below it),
// the mean distance |allowable - x*|, sweeps whose allowable interval holds x*, and the mean runs.
//   bench_sweep_fit [--n 500] [--seeds 200]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "numeric/subset_cases.hpp"
#include "sampling/monotone_fit.hpp"

using namespace truss::sampling;

namespace {

struct Tally {
  int void_ = 0, unsafe = 0, holds = 0, found = 0;
  double distance = 0.0, runs = 0.0;
  void add(const Allowable& a, double truth, double runs_made) {
    runs += runs_made;
    if (a.status != AllowableStatus::found) {
      ++void_;
      return;
    }
    ++found;
    unsafe += a.value < truth ? 1 : 0;
    distance += std::abs(a.value - truth);
    holds += !(a.lower > truth) && !(a.upper < truth) ? 1 : 0;
  }
  void print(const char* name, int seeds) const {
    std::printf("| %s | %d | %d | %.3f | %d | %.0f |\n", name, void_, unsafe, distance / std::max(found, 1), holds,
                runs / seeds);
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::int64_t n = 500;
  int seeds = 200;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--n") == 0) n = std::atoll(argv[i + 1]);
    if (std::strcmp(argv[i], "--seeds") == 0) seeds = std::atoi(argv[i + 1]);
  }
  const std::vector<double> x{4.0, 4.25, 4.5, 4.75, 5.0, 5.25};
  const double target = 1e-6, truth = -normal_quantile(target);
  Tally today, walk, fit;
  for (int s = 1; s <= seeds; ++s) {
    std::vector<ProbabilityBounds> b_today, b_new;
    std::vector<SweepEstimate> est;
    double runs_today = 0.0, runs_new = 0.0;
    for (std::size_t k = 0; k < x.size(); ++k) {
      SubsetOptions o;
      o.dims = 10;
      o.n_per_level = n;
      o.seed = splitmix_at(static_cast<std::uint64_t>(s), k);
      const truss::testing::LinearCase c{x[k]};
      const SubsetSummary mm = truss::testing::run_subset(o, c);
      b_today.push_back(calc_lognormal_bounds(mm.p, mm.cov_bound, 0.95));
      runs_today += static_cast<double>(mm.runs);
      o.proposal = SubsetProposal::adaptive_conditional;
      const SubsetSummary acs = truss::testing::run_subset(o, c);
      b_new.push_back(calc_lognormal_bounds(acs.p, acs.cov_interval, 0.95));
      runs_new += static_cast<double>(acs.runs);
      SweepEstimate e;
      e.x = x[k];
      e.p = acs.p;
      e.cov = acs.cov_interval;
      e.untrusted = find_untrusted_reason(acs);
      est.push_back(e);
    }
    today.add(find_allowable_on_side(x, b_today, +1, target), truth, runs_today);
    walk.add(find_allowable_on_side(x, b_new, +1, target), truth, runs_new);
    fit.add(calc_monotone_fit(est, +1, target, 0.95).allowable, truth, runs_new);
  }
  std::printf("N = %lld, %d seeds, true crossing %.4f\n\n", static_cast<long long>(n), seeds, truth);
  std::printf("| way | no allowable | on the unsafe side | mean distance | interval holds x* | runs a sweep |\n");
  std::printf("|---|---:|---:|---:|---:|---:|\n");
  today.print("walk (modified Metropolis, cov_bound)", seeds);
  walk.print("walk (aCS, cov_interval)", seeds);
  fit.print("monotone fit (aCS, cov_interval)", seeds);
  return 0;
}
