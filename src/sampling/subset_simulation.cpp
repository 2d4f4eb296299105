// subset_simulation.cpp — the state machine of subset simulation; the method, its estimators and
// their sources are stated in subset_simulation.hpp. Byte formats: subset_bytes.cpp.
#include "sampling/subset_simulation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "sampling/sampling.hpp"
#include "sampling/subset_keys.hpp"

namespace truss::sampling {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A NaN margin is safe at every level.
double order_key(double margin) { return std::isnan(margin) ? kInf : margin; }

// The interval CoV (header, "interval CoV"): the lag-1 and bound variances of ln p^ weighted by G
// lineages against two.
double calc_interval_cov(double cov_lag1, double cov_bound, double lineages) {
  if (!std::isfinite(cov_lag1) || !std::isfinite(cov_bound)) return kInf;
  constexpr double kBoundWeight = 2.0;
  const double s1 = std::log1p(cov_lag1 * cov_lag1), sb = std::log1p(cov_bound * cov_bound);
  return std::sqrt(std::expm1((lineages * s1 + kBoundWeight * sb) / (lineages + kBoundWeight)));
}

// Modified Metropolis (Au & Beck 2001, sec. 3.1) for chain c at (level, step) from state z: per
// dimension a uniform proposal of half-width a, kept with probability min(1, phi(e) / phi(z)).
// Returns whether xi differs from z.
bool calc_candidate(const SubsetOptions& o, int level, int step, std::int64_t chain, const double* z, double* xi) {
  const std::uint64_t propose = counter_run_state(o.seed, chain, subset_stream(level, step, kStreamPropose));
  const std::uint64_t accept = counter_run_state(o.seed, chain, subset_stream(level, step, kStreamAccept));
  bool moved = false;
  for (int j = 0; j < o.dims; ++j) {
    const double u1 = to_open_unit(splitmix_at(propose, static_cast<std::uint64_t>(j)));
    const double u2 = to_open_unit(splitmix_at(accept, static_cast<std::uint64_t>(j)));
    const double e = z[j] + o.proposal_half_width * (2.0 * u1 - 1.0);
    const double ratio = std::exp(0.5 * (z[j] * z[j] - e * e));  // phi(e) / phi(z)
    xi[j] = u2 < ratio ? e : z[j];
    moved = moved || xi[j] != z[j];
  }
  return moved;
}

// The step's proposal of conditional sampling (Papaioannou et al. 2015, sec. 5): each dimension's
// spread sigma_j and rho_j = sqrt(1 - sigma_j^2), the same for every chain of the step.
struct ConditionalStep {
  std::vector<double> sigma, rho;
};

// Conditional sampling for chain c at (level, step) from z: the whole candidate
// v_j = rho_j z_j + sigma_j n_j, the normals n_j keyed by (chain, level, step, j) and found in one
// batch (normal_quantiles: normal_quantile's bits). `n` is work space of dims values.
bool calc_conditional_candidate(const SubsetOptions& o, int level, int step, std::int64_t chain, const double* z,
                                const ConditionalStep& p, double* n, double* xi) {
  const std::uint64_t propose = counter_run_state(o.seed, chain, subset_stream(level, step, kStreamPropose));
  for (int j = 0; j < o.dims; ++j) n[j] = to_open_unit(splitmix_at(propose, static_cast<std::uint64_t>(j)));
  normal_quantiles(n, n, static_cast<std::size_t>(o.dims));
  bool moved = false;
  for (int j = 0; j < o.dims; ++j) {
    const auto k = static_cast<std::size_t>(j);
    xi[j] = p.rho[k] * z[j] + p.sigma[k] * n[j];
    moved = moved || xi[j] != z[j];
  }
  return moved;
}

}  // namespace

std::string SubsetOptions::validate() const {
  if (dims < 1) return fmt::format("dims: {} (at least one sampling dimension)", dims);
  if (n_per_level < 2) return fmt::format("n_per_level: {} (at least 2 samples per level)", n_per_level);
  if (!(p0 > 0.0 && p0 <= 0.5)) return fmt::format("p0: {} (must lie in (0, 0.5])", p0);
  const double chains = p0 * static_cast<double>(n_per_level);
  if (std::abs(chains - std::round(chains)) > 1e-9 * chains || std::round(chains) < 1.0)
    return fmt::format("p0: n_per_level * p0 = {} * {} = {} is not a whole number of chains >= 1", n_per_level, p0,
                       chains);
  if (max_levels < 1 || max_levels > 1000) return fmt::format("max_levels: {} (must lie in [1, 1000])", max_levels);
  if (!(proposal_half_width >= kMinProposalHalfWidth && proposal_half_width <= kMaxProposalHalfWidth))
    return fmt::format("proposal_half_width: {:.17g} (must lie in [{}, {}] standard deviations)", proposal_half_width,
                       kMinProposalHalfWidth, kMaxProposalHalfWidth);
  // The run cap N + (max_levels - 1) (N - N_c) and a level's N x dims normals, in 64-bit counts
  // (n_chains() is at most N here).
  constexpr std::int64_t kMaxCount = std::int64_t{1} << 53;
  std::int64_t steps = 0, total = 0, normals = 0;
  if (__builtin_mul_overflow(static_cast<std::int64_t>(max_levels - 1), n_per_level - n_chains(), &steps) ||
      __builtin_add_overflow(n_per_level, steps, &total) || total > kMaxCount)
    return fmt::format("n_per_level: {} samples per level over max_levels = {} levels is more than 2^53 runs",
                       n_per_level, max_levels);
  if (__builtin_mul_overflow(n_per_level, static_cast<std::int64_t>(dims), &normals) || normals > kMaxCount)
    return fmt::format("n_per_level: {} samples per level of {} dimensions is more than 2^53 numbers", n_per_level,
                       dims);
  return "";
}

std::int64_t SubsetOptions::n_chains() const { return std::llround(p0 * static_cast<double>(n_per_level)); }

std::int64_t SubsetOptions::max_evaluations() const {
  return n_per_level + static_cast<std::int64_t>(max_levels - 1) * (n_per_level - n_chains());
}

void calc_round_normals(const SubsetOptions& o, const SubsetRound& r, std::int64_t k, double* z) {
  if (k < 0 || k >= r.n_points) throw std::out_of_range(fmt::format("point {} of a round of {}", k, r.n_points));
  if (r.step == 0) {
    calc_round_uniforms(o, r, k, z);
    normal_quantiles(z, z, static_cast<std::size_t>(o.dims));
    return;
  }
  std::copy_n(r.z.data() + k * o.dims, o.dims, z);
}

void calc_round_uniforms(const SubsetOptions& o, const SubsetRound& r, std::int64_t k, double* u) {
  if (k < 0 || k >= r.n_points) throw std::out_of_range(fmt::format("point {} of a round of {}", k, r.n_points));
  if (r.step == 0) {
    const std::uint64_t state = counter_run_state(o.seed, k, subset_stream(0, 0, kStreamLevel0));
    for (int j = 0; j < o.dims; ++j)
      u[j] = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(j)));
    return;
  }
  // Phi(z) kept strictly inside (0, 1) like the keyed uniforms (|z| > 8.3 rounds to an end).
  for (int j = 0; j < o.dims; ++j)
    u[j] = calc_open_normal_cdf(r.z[static_cast<std::size_t>(k * o.dims + j)]);
}

SubsetSimulation::SubsetSimulation(const SubsetOptions& o) : opt_(o) {
  if (const std::string why = o.validate(); !why.empty()) throw std::invalid_argument(why);
  levels_.emplace_back();
  parents_.emplace_back();  // level 0's samples have no parent
  round_.n_points = o.n_per_level;
  samples_.reserve(static_cast<std::size_t>(o.n_per_level));
  z_.reserve(static_cast<std::size_t>(o.n_per_level * o.dims));
}

std::int64_t SubsetSimulation::chain_length(std::int64_t c) const {
  const std::int64_t nc = opt_.n_chains();
  return opt_.n_per_level / nc + (c < opt_.n_per_level % nc ? 1 : 0);
}

void SubsetSimulation::push_sample(const Sample& s, const double* z) {
  samples_.push_back(s);
  z_.insert(z_.end(), z, z + opt_.dims);
}

void SubsetSimulation::add_margins(std::span<const double> margins) {
  if (done()) throw std::logic_error("subset simulation: margins given after it finished");
  if (static_cast<std::int64_t>(margins.size()) != round_.n_points)
    throw std::invalid_argument(fmt::format("subset simulation: {} margins for a round of {} points", margins.size(),
                                            round_.n_points));
  const int step = round_.step;
  if (step == 0) take_level0(margins);
  else take_step(margins);
  evaluations_ += round_.n_points;
  rounds_ = round_.index + 1;
  if (step == 0) finish_level();
  else advance(step);
}

void SubsetSimulation::take_level0(std::span<const double> margins) {
  std::vector<double> z(static_cast<std::size_t>(opt_.dims));
  for (std::int64_t k = 0; k < round_.n_points; ++k) {
    calc_round_normals(opt_, round_, k, z.data());
    push_sample({margins[static_cast<std::size_t>(k)], k, 0, round_.first_evaluation + k, k}, z.data());
  }
  levels_.back().runs = round_.n_points;
  for (double m : margins) levels_.back().unusable += std::isnan(m) ? 1 : 0;
}

// One Markov step of every chain that has states left: an evaluated candidate in the level's
// domain is the new state; otherwise (rejected, or xi = z and not evaluated) the state repeats.
void SubsetSimulation::take_step(std::span<const double> margins) {
  SubsetLevel& level = levels_.back();
  const int step = round_.step;
  std::size_t p = 0;  // next point of the round (round_.chains ascending)
  const auto d = static_cast<std::size_t>(opt_.dims);
  const std::int64_t runs_before = level.runs, moved_before = level.moved;
  for (std::int64_t c = 0; c < opt_.n_chains(); ++c) {
    if (chain_length(c) <= step) continue;
    const auto head = static_cast<std::size_t>(head_[static_cast<std::size_t>(c)]);
    Sample s = samples_[head];
    s.step = step;
    const double* candidate = nullptr;
    if (p < round_.chains.size() && round_.chains[p] == c) {
      ++level.runs;
      level.unusable += std::isnan(margins[p]) ? 1 : 0;
      if (margins[p] <= domain_) {  // NaN: not in the domain
        s.margin = margins[p];
        s.evaluation = round_.first_evaluation + static_cast<std::int64_t>(p);
        candidate = round_.z.data() + p * d;
        ++level.moved;
      }
      ++p;
    }
    ++level.steps;
    head_[static_cast<std::size_t>(c)] = static_cast<std::int64_t>(samples_.size());
    samples_.push_back(s);
    const std::size_t at = z_.size();
    z_.resize(at + d);  // then the state: the candidate kept, or the head's state repeated
    std::copy_n(candidate ? candidate : z_.data() + head * d, d, z_.data() + at);
  }
  adapt_scale(step, level.runs - runs_before, level.moved - moved_before);
}

// Adaptive conditional sampling: lambda after step `step` from that step's counts (see the header).
void SubsetSimulation::adapt_scale(int step, std::int64_t evaluated, std::int64_t kept) {
  if (opt_.proposal != SubsetProposal::adaptive_conditional || evaluated == 0) return;
  const double rate = static_cast<double>(kept) / static_cast<double>(evaluated);
  scale_ = std::exp(std::log(scale_) + (rate - SubsetOptions::kTargetAcceptance) / std::sqrt(step));
}

// sigma0_j: the sample standard deviation of the level's seeds (its first N_c samples), in the
// seeds' order; 1 with a single seed.
void SubsetSimulation::calc_seed_spread() {
  const auto nc = static_cast<std::size_t>(opt_.n_chains()), d = static_cast<std::size_t>(opt_.dims);
  spread0_.assign(d, 1.0);
  if (nc < 2) return;
  for (std::size_t j = 0; j < d; ++j) {
    double mean = 0.0, ss = 0.0;
    for (std::size_t c = 0; c < nc; ++c) mean += z_[c * d + j];
    mean /= static_cast<double>(nc);
    for (std::size_t c = 0; c < nc; ++c) ss += (z_[c * d + j] - mean) * (z_[c * d + j] - mean);
    spread0_[j] = std::sqrt(ss / static_cast<double>(nc - 1));
  }
}

// After step `done_step` of the current level: plan the next step with points to evaluate,
// stepping over steps where no chain moves; finish the level after its last step.
void SubsetSimulation::advance(int done_step) {
  const std::int64_t longest = chain_length(0);
  for (int step = done_step + 1; step < longest; ++step) {
    plan_step(step);
    if (round_.n_points > 0) return;
    take_step({});
  }
  finish_level();
}

void SubsetSimulation::plan_step(int step) {
  SubsetRound r;
  r.index = rounds_;
  r.first_evaluation = evaluations_;
  r.level = static_cast<int>(levels_.size()) - 1;
  r.step = step;
  r.threshold = domain_;
  std::vector<double> xi(static_cast<std::size_t>(opt_.dims)), n(xi.size());
  const bool adaptive = opt_.proposal == SubsetProposal::adaptive_conditional;
  ConditionalStep p;
  if (adaptive)
    for (double s0 : spread0_) {
      const double s = std::min(1.0, scale_ * s0);
      p.sigma.push_back(s);
      p.rho.push_back(std::sqrt(1.0 - s * s));
    }
  for (std::int64_t c = 0; c < opt_.n_chains(); ++c) {
    if (chain_length(c) <= step) continue;
    const double* z = z_.data() + head_[static_cast<std::size_t>(c)] * opt_.dims;
    const bool moved = adaptive ? calc_conditional_candidate(opt_, r.level, step, c, z, p, n.data(), xi.data())
                                : calc_candidate(opt_, r.level, step, c, z, xi.data());
    if (!moved) continue;
    r.chains.push_back(c);
    r.z.insert(r.z.end(), xi.begin(), xi.end());
  }
  r.n_points = static_cast<std::int64_t>(r.chains.size());
  round_ = std::move(r);
}

// The level's N samples are complete: its threshold and conditional probability; then the next
// level, or the end.
void SubsetSimulation::finish_level() {
  const auto n = static_cast<std::int64_t>(samples_.size());
  const std::int64_t nc = opt_.n_chains();
  std::vector<std::int64_t> order(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  const auto less = [&](std::int64_t a, std::int64_t b) {
    const double ka = order_key(samples_[static_cast<std::size_t>(a)].margin);
    const double kb = order_key(samples_[static_cast<std::size_t>(b)].margin);
    return ka < kb || (ka == kb && a < b);
  };
  std::nth_element(order.begin(), order.begin() + (nc - 1), order.end(), less);
  std::sort(order.begin(), order.begin() + nc, less);
  const double b = order_key(samples_[static_cast<std::size_t>(order[static_cast<std::size_t>(nc - 1)])].margin);
  SubsetLevel& level = levels_.back();
  if (levels_.size() > 1 && level.moved == 0) {  // the chains stood still: the level repeats its seeds
    level.threshold = level.probability = level.cov = kNaN;
    status_ = SubsetStatus::chains_stuck;
    const std::string proposal =
        opt_.proposal == SubsetProposal::adaptive_conditional
            ? fmt::format("adaptive conditional sampling, lambda = {:.4g}", scale_)
            : fmt::format("proposal_half_width = {:.17g}", opt_.proposal_half_width);
    message_ = fmt::format("level {}: no Markov chain moved in its {} steps (acceptance 0, {}): the level only "
                           "repeats its seeds, so there is no estimate", levels_.size() - 1, level.steps, proposal);
    round_ = SubsetRound{};
    round_.index = rounds_;
    round_.first_evaluation = evaluations_;
    return;
  }
  const bool reached = b <= 0.0;
  const bool capped = !reached && static_cast<int>(levels_.size()) >= opt_.max_levels;
  const bool stuck = !reached && !capped && b >= domain_;  // level 0: more than N - N_c NaN margins
  const bool last = reached || capped || stuck;
  const double threshold = last ? 0.0 : b;
  std::int64_t count = 0;
  for (const Sample& s : samples_) count += s.margin <= threshold ? 1 : 0;
  const double P = static_cast<double>(count) / static_cast<double>(n);
  level.threshold = threshold;
  level.probability = P;
  if (opt_.proposal == SubsetProposal::adaptive_conditional && levels_.size() > 1) level.scale = scale_;
  level.ties = last ? 0 : count - nc;
  level.gamma = levels_.size() == 1 ? 0.0 : calc_gamma(threshold, P);
  level.cov = P > 0.0 ? std::sqrt((1.0 - P) / (static_cast<double>(n) * P) * (1.0 + level.gamma)) : kInf;
  add_lineage(threshold, P);
  if (!last) {
    std::vector<std::int64_t> seeds(order.begin(), order.begin() + nc);
    std::sort(seeds.begin(), seeds.end());  // chains in sample order
    start_level(b, seeds);
    return;
  }
  status_ = reached ? SubsetStatus::converged : capped ? SubsetStatus::level_cap : SubsetStatus::no_progress;
  message_ = reached ? fmt::format("the failure domain was reached at level {}", levels_.size() - 1)
             : capped ? fmt::format("max_levels = {} reached with threshold {} > 0: the estimate counts the last "
                                    "level's failures only", opt_.max_levels, b)
                      : fmt::format("level {}: the threshold does not decrease ({} after {}): the margin is flat "
                                    "or mostly NaN there", levels_.size() - 1, b, domain_);
  round_ = SubsetRound{};
  round_.index = rounds_;
  round_.first_evaluation = evaluations_;
}

void SubsetSimulation::start_level(double threshold, const std::vector<std::int64_t>& seeds) {
  std::vector<Sample> samples;
  std::vector<double> z;
  samples.reserve(static_cast<std::size_t>(opt_.n_per_level));
  z.reserve(static_cast<std::size_t>(opt_.n_per_level * opt_.dims));
  head_.assign(seeds.size(), 0);
  for (std::size_t c = 0; c < seeds.size(); ++c) {
    const Sample& s = samples_[static_cast<std::size_t>(seeds[c])];
    samples.push_back({s.margin, static_cast<std::int64_t>(c), 0, s.evaluation, s.root});
    const double* zs = z_.data() + seeds[c] * opt_.dims;
    z.insert(z.end(), zs, zs + opt_.dims);
    head_[c] = static_cast<std::int64_t>(c);
  }
  std::vector<std::int64_t>& parent = parents_.emplace_back(seeds.size());
  for (std::size_t c = 0; c < seeds.size(); ++c) parent[c] = samples_[static_cast<std::size_t>(seeds[c])].chain;
  samples_ = std::move(samples);
  z_ = std::move(z);
  domain_ = threshold;
  if (opt_.proposal == SubsetProposal::adaptive_conditional) calc_seed_spread();
  levels_.emplace_back();
  advance(0);
}

// gamma_k of Au & Beck eq. 27-28 over the chains of the current level (lengths may differ by one).
double SubsetSimulation::calc_gamma(double threshold, double p) const {
  if (!(p > 0.0 && p < 1.0)) return 0.0;
  std::vector<std::vector<char>> hit(head_.size());
  for (const Sample& s : samples_) hit[static_cast<std::size_t>(s.chain)].push_back(s.margin <= threshold ? 1 : 0);
  const double n = static_cast<double>(samples_.size()), r0 = p * (1.0 - p);
  double gamma = 0.0;
  for (std::size_t lag = 1; lag < hit.front().size(); ++lag) {
    double both = 0.0, pairs = 0.0;
    for (const auto& h : hit) {
      for (std::size_t s = 0; s + lag < h.size(); ++s) both += h[s] & h[s + lag];
      pairs += h.size() > lag ? static_cast<double>(h.size() - lag) : 0.0;
    }
    gamma += 2.0 * (pairs / n) * (both / pairs - p * p) / r0;
  }
  return gamma;
}

void SubsetSimulation::add_lineage(double threshold, double p) {
  if (lineage_.empty()) lineage_.assign(samples_.size(), 0.0);  // level 0: one root per sample
  std::vector<double>& unit = unit_terms_.emplace_back(levels_.size() == 1 ? samples_.size() : head_.size(), 0.0);
  if (!(p > 0.0)) return;  // the estimate is 0: no first-order term (cov is infinite)
  const double scale = 1.0 / (static_cast<double>(samples_.size()) * p);
  for (const Sample& s : samples_) {
    const double term = ((s.margin <= threshold ? 1.0 : 0.0) - p) * scale;
    lineage_[static_cast<std::size_t>(s.root)] += term;
    unit[static_cast<std::size_t>(s.chain)] += term;
  }
}

// Level k's unit terms summed over their ancestors at level g <= k (a unit: a chain; at level 0 a sample).
std::vector<double> SubsetSimulation::calc_terms_at(std::size_t k, std::size_t g) const {
  std::vector<double> out(unit_terms_[g].size(), 0.0);
  for (std::size_t u = 0; u < unit_terms_[k].size(); ++u) {
    std::size_t a = u;
    for (std::size_t l = k; l > g; --l) a = static_cast<std::size_t>(parents_[l][a]);
    out[a] += unit_terms_[k][u];
  }
  return out;
}

double SubsetSimulation::calc_lag_cov(int lag) const {
  double v = 0.0;
  const std::size_t m = unit_terms_.size();
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t g = lag < 0 || k < static_cast<std::size_t>(lag) ? 0 : k - static_cast<std::size_t>(lag);
    const std::vector<double> a = calc_terms_at(k, g);
    for (std::size_t j = k; j < m; ++j) {
      const std::vector<double> b = j == k ? a : calc_terms_at(j, g);
      double c = 0.0;
      for (std::size_t u = 0; u < a.size(); ++u) c += a[u] * b[u];
      v += (j == k ? 1.0 : 2.0) * c;
    }
  }
  return std::sqrt(std::max(v, 0.0));
}

SubsetSummary SubsetSimulation::calc_summary() const {
  SubsetSummary s;
  s.status = status_;
  s.message = message_;
  s.runs = evaluations_;
  s.rounds = rounds_;
  s.levels = levels_;
  if (!done()) {
    s.levels.pop_back();  // the level being sampled has no estimate yet
    return s;
  }
  double p = 1.0, cov2 = 0.0, cov_sum = 0.0;
  for (const SubsetLevel& l : levels_) {
    p *= l.probability;
    cov2 += l.cov * l.cov;
    cov_sum += l.cov;
  }
  s.p = p;
  s.cov = std::sqrt(cov2);
  double lineage2 = 0.0, lineage4 = 0.0;
  for (double x : lineage_) {
    lineage2 += x * x;
    lineage4 += x * x * x * x;
  }
  s.lineage_groups = lineage4 > 0.0 ? lineage2 * lineage2 / lineage4 : 0.0;
  s.cov_lineage = p > 0.0 ? std::sqrt(lineage2) : kInf;
  s.cov_bound = p > 0.0 ? std::max(cov_sum, s.cov_lineage) : kInf;
  s.cov_lag1 = p > 0.0 ? calc_lag_cov(1) : kInf;
  s.cov_interval = calc_interval_cov(s.cov_lag1, s.cov_bound, s.lineage_groups);
  std::vector<std::int64_t> roots;
  for (const Sample& x : samples_) roots.push_back(x.root);
  std::sort(roots.begin(), roots.end());
  s.lineages = std::unique(roots.begin(), roots.end()) - roots.begin();
  s.beta = -normal_quantile(p);
  if (status_ == SubsetStatus::chains_stuck)
    s.p = s.beta = s.cov = s.cov_lineage = s.cov_bound = s.cov_lag1 = s.cov_interval = kNaN;
  return s;
}

int SubsetSummary::calc_plateau_levels() const {
  int n = 0;
  for (std::size_t k = 0; k + 1 < levels.size(); ++k) {
    const double b = levels[k].threshold, next = levels[k + 1].threshold;
    n += b > 0.0 && b - next < kPlateauShare * b ? 1 : 0;
  }
  return n;
}

std::string find_untrusted_reason(const SubsetSummary& s) {
  switch (s.status) {
    case SubsetStatus::running: return "not finished";
    case SubsetStatus::chains_stuck: return "no estimate (the Markov chains never moved)";
    case SubsetStatus::no_progress: return "the thresholds stopped decreasing (a flat or mostly unusable margin)";
    case SubsetStatus::level_cap:  // stands: the last level's share bounds p from above (the safe side)
    case SubsetStatus::converged: break;
  }
  const int plateau = s.calc_plateau_levels();
  if (plateau >= SubsetSummary::kPlateauLevels)
    return fmt::format("the margin is nearly flat over {} levels (each threshold within {:g} % of the previous "
                       "one): the estimate can lie far below p, beyond its interval", plateau,
                       100.0 * SubsetSummary::kPlateauShare);
  return "";
}

std::vector<SubsetSample> SubsetSimulation::calc_failure_samples() const {
  std::vector<SubsetSample> out;
  if (!done()) return out;
  for (std::size_t i = 0; i < samples_.size(); ++i) {
    const Sample& s = samples_[i];
    if (!(s.margin <= 0.0)) continue;
    const double* z = z_.data() + i * static_cast<std::size_t>(opt_.dims);
    out.push_back({s.evaluation, s.margin, std::vector<double>(z, z + opt_.dims)});
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.evaluation < b.evaluation; });
  const auto same = [](const auto& a, const auto& b) { return a.evaluation == b.evaluation; };
  out.erase(std::unique(out.begin(), out.end(), same), out.end());
  return out;
}

}  // namespace truss::sampling
