// importance_sampling.cpp — the cross-entropy state machine; the method, its sources and keys are
// stated in importance_sampling.hpp.
#include "sampling/importance_sampling.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "sampling/byte_image.hpp"
#include "sampling/sampling.hpp"

namespace truss::sampling {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::uint32_t kRoundTag = 0x31525349;  // "ISR1"

double order_key(double margin) { return std::isnan(margin) ? kInf : margin; }

// z of point k, z = mu + n with n the keyed standard normals (carried by g in the final round);
// returns ln phi(z) - ln h(z) = |mu|^2 / 2 - mu.z - ln g(n) / phi(n).
double calc_point(const ImportanceOptions& o, const ImportanceRound& r, std::int64_t k, double* z,
                  const Deviation* g) {
  if (k < 0 || k >= r.n_points) throw std::out_of_range(fmt::format("point {} of a round of {}", k, r.n_points));
  const std::uint64_t state = counter_run_state(o.seed, r.first_evaluation + k, kTagImportance);
  const auto d = static_cast<std::size_t>(o.dims);
  for (std::size_t j = 0; j < d; ++j) z[j] = normal_quantile(to_open_unit(splitmix_at(state, j)));
  double log_g = 0.0;
  if (g != nullptr && r.final) {
    g->transport(to_open_unit(splitmix_at(state, d)), z);
    log_g = g->calc_log_ratio(z);
  }
  double mm = 0.0, mz = 0.0;
  for (std::size_t j = 0; j < d; ++j) {
    z[j] += r.mean[j];
    mm += r.mean[j] * r.mean[j];
    mz += r.mean[j] * z[j];
  }
  return 0.5 * mm - mz - log_g;
}

}  // namespace

std::string ImportanceOptions::validate() const {
  if (dims < 1) return fmt::format("dims: {} (at least one sampling dimension)", dims);
  if (!(rho > 0.0 && rho <= 0.5)) return fmt::format("rho: {} (must lie in (0, 0.5])", rho);
  if (n_per_level < 2 || rho * static_cast<double>(n_per_level) < 1.0)
    return fmt::format("n_per_level: {} (at least 2, and rho n_per_level >= 1 elite point)", n_per_level);
  if (n_final < 2) return fmt::format("n_final: {} (at least 2 runs for a variance)", n_final);
  if (max_levels < 1 || max_levels > 1000) return fmt::format("max_levels: {} (must lie in [1, 1000])", max_levels);
  constexpr std::int64_t kMaxCount = std::int64_t{1} << 53;
  std::int64_t levels = 0, total = 0, normals = 0;
  if (__builtin_mul_overflow(static_cast<std::int64_t>(max_levels), n_per_level, &levels) ||
      __builtin_add_overflow(levels, n_final, &total) || total > kMaxCount)
    return fmt::format("n_per_level: max_levels x n_per_level + n_final is more than 2^53 runs");
  if (__builtin_mul_overflow(std::max(n_per_level, n_final), static_cast<std::int64_t>(dims), &normals) ||
      normals > kMaxCount)
    return fmt::format("n_final: a round of {} dimensions is more than 2^53 numbers", dims);
  return "";
}

std::string ImportanceRound::encode() const {
  detail::ByteWriter w;
  w.put(kRoundTag);
  w.put(index);
  w.put(first_evaluation);
  w.put(static_cast<std::int32_t>(level));
  w.put(static_cast<std::int32_t>(final ? 1 : 0));
  w.put(n_points);
  w.put_all(mean);
  return std::move(w.out);
}

ImportanceRound ImportanceRound::decode(std::string_view bytes, int dims) {
  detail::ByteReader r{bytes, "importance round"};
  if (r.get<std::uint32_t>() != kRoundTag) throw std::runtime_error("importance round: not an encoded round (tag)");
  ImportanceRound s;
  s.index = r.get<std::int64_t>();
  s.first_evaluation = r.get<std::int64_t>();
  s.level = r.get<std::int32_t>();
  const auto final = r.get<std::int32_t>();
  s.final = final == 1;
  s.n_points = r.get<std::int64_t>();
  s.mean = r.get_all<double>();
  r.expect_end();
  const auto d = static_cast<std::size_t>(dims);
  if (s.index < 0 || s.first_evaluation < 0 || s.level < 0 || (final != 0 && final != 1) || s.n_points < 0 ||
      s.mean.size() != d)
    throw std::runtime_error(fmt::format("importance round: inconsistent plan (level {}, {} points, {} means for {} "
                                         "dimensions)", s.level, s.n_points, s.mean.size(), dims));
  return s;
}

void calc_round_normals(const ImportanceOptions& o, const ImportanceRound& r, std::int64_t k, double* z,
                        const Deviation* g) {
  calc_point(o, r, k, z, g);
}

void calc_round_uniforms(const ImportanceOptions& o, const ImportanceRound& r, std::int64_t k, double* u,
                         const Deviation* g) {
  calc_point(o, r, k, u, g);
  for (int j = 0; j < o.dims; ++j) u[j] = calc_open_normal_cdf(u[j]);
}

double calc_round_log_weight(const ImportanceOptions& o, const ImportanceRound& r, std::int64_t k,
                             const Deviation* g) {
  std::vector<double> z(static_cast<std::size_t>(o.dims));
  return calc_point(o, r, k, z.data(), g);
}

CrossEntropySampler::CrossEntropySampler(const ImportanceOptions& o) : opt_(o) {
  if (const std::string why = o.validate(); !why.empty()) throw std::invalid_argument(why);
  mean_.assign(static_cast<std::size_t>(o.dims), 0.0);
  mean_var_.assign(static_cast<std::size_t>(o.dims), 0.0);
  plan(0, false);
}

void CrossEntropySampler::plan(int level, bool final) {
  ImportanceRound r;
  r.index = rounds_;
  r.first_evaluation = evaluations_;
  r.level = level;
  r.final = final;
  r.n_points = final ? opt_.n_final : opt_.n_per_level;
  r.mean = mean_;
  round_ = std::move(r);
}

void CrossEntropySampler::add_margins(std::span<const double> margins, std::span<const double> log_ratio) {
  if (done_) throw std::logic_error("importance sampling: margins given after it finished");
  const auto n = static_cast<std::size_t>(round_.n_points);
  if (margins.size() != n || !(log_ratio.empty() || log_ratio.size() == n))
    throw std::invalid_argument(fmt::format("importance sampling: {} margins and {} ratios for a round of {} points",
                                            margins.size(), log_ratio.size(), n));
  evaluations_ += round_.n_points;
  rounds_ = round_.index + 1;
  if (round_.final) {
    final_ = round_;
    final_margins_.assign(margins.begin(), margins.end());
    done_ = true;
    return;
  }
  take_level(margins, log_ratio);
}

// One cross-entropy level: its threshold, the update of the density, and what comes next.
void CrossEntropySampler::take_level(std::span<const double> margins, std::span<const double> log_ratio) {
  const auto n = static_cast<std::size_t>(round_.n_points);
  std::vector<double> key(margins.begin(), margins.end());
  for (double& m : key) m = order_key(m);
  const auto m = static_cast<std::size_t>(std::ceil(opt_.rho * static_cast<double>(n))) - 1;
  std::nth_element(key.begin(), key.begin() + static_cast<std::ptrdiff_t>(m), key.end());
  ImportanceLevel lv;
  lv.threshold = std::max(0.0, key[m]);
  lv.runs = round_.n_points;
  for (double x : margins) lv.unusable += std::isnan(x) ? 1 : 0;
  for (double v : round_.mean) lv.shift += v * v;
  lv.shift = std::sqrt(lv.shift);
  // The elites' z and ln W; the update from W / max W.
  std::vector<std::size_t> elite;
  for (std::size_t k = 0; k < n; ++k)
    if (margins[k] <= lv.threshold) elite.push_back(k);
  lv.elites = static_cast<std::int64_t>(elite.size());
  if (lv.elites > 0) lv.moved = update_mean(elite, log_ratio, lv.elite_ess);
  for (double v : mean_var_) lv.mean_noise += v;
  const bool reached = lv.threshold <= 0.0;
  const bool no_progress =
      lv.moved == 0 || (!levels_.empty() && lv.threshold >= levels_.back().threshold);
  levels_.push_back(lv);
  const int t = static_cast<int>(levels_.size());
  if (reached) {
    status_ = ImportanceStatus::converged;
    message_ = fmt::format("the failure domain was reached at level {}", t - 1);
  } else if (no_progress) {
    status_ = ImportanceStatus::no_progress;
    message_ = fmt::format("level {}: {}: the final runs use the last density", t - 1,
                           lv.moved == 0 ? "the density did not move (no mean component by 3 standard errors)"
                                         : fmt::format("the threshold does not decrease ({:.6g})", lv.threshold));
  } else if (t >= opt_.max_levels) {
    status_ = ImportanceStatus::level_cap;
    message_ = fmt::format("max_levels = {} ended with the threshold at {:.6g} > 0: the final runs use the last "
                           "density", opt_.max_levels, lv.threshold);
  } else {
    plan(t, false);
    return;
  }
  plan(t, true);
}

// mu <- the cross-entropy mean of the elites, component by component where it moved significantly
// (see the header); returns the components moved, and the weights' ESS in `ess`.
int CrossEntropySampler::update_mean(const std::vector<std::size_t>& elite, std::span<const double> log_ratio,
                                     double& ess) {
  const auto d = static_cast<std::size_t>(opt_.dims);
  std::vector<double> z(elite.size() * d), w(elite.size());
  for (std::size_t i = 0; i < elite.size(); ++i) {
    const auto k = static_cast<std::int64_t>(elite[i]);
    w[i] = calc_point(opt_, round_, k, z.data() + i * d, nullptr) + (log_ratio.empty() ? 0.0 : log_ratio[elite[i]]);
  }
  const double top = *std::max_element(w.begin(), w.end());
  if (!std::isfinite(top)) {  // every elite has weight 0 under the law (or a ratio that is not a number)
    ess = 0.0;
    return 0;
  }
  double sw = 0.0, sw2 = 0.0;
  for (double& x : w) {
    x = std::exp(x - top);
    sw += x;
    sw2 += x * x;
  }
  ess = sw * sw / sw2;
  int moved = 0;
  for (std::size_t j = 0; j < d; ++j) {
    double mu = 0.0, var = 0.0;
    for (std::size_t i = 0; i < elite.size(); ++i) mu += w[i] * z[i * d + j];
    mu /= sw;
    for (std::size_t i = 0; i < elite.size(); ++i) var += w[i] * w[i] * (z[i * d + j] - mu) * (z[i * d + j] - mu);
    if (std::abs(mu - mean_[j]) <= ImportanceOptions::kSignificance * std::sqrt(var) / sw) continue;
    mean_[j] = mu;
    mean_var_[j] = var / (sw * sw);
    ++moved;
  }
  return moved;
}

std::string CrossEntropySampler::find_refusal() const {
  if (!done_) return "not finished";
  const double noise = levels_.empty() ? 0.0 : levels_.back().mean_noise;
  if (noise <= ImportanceOptions::kMaxMeanNoise) return "";
  return fmt::format("the importance density's mean is too noisy to weight by: the sum of its components' squared "
                     "standard errors is {:.3g} (at most {:g}); many inputs each move it a little: use subset "
                     "simulation", noise, ImportanceOptions::kMaxMeanNoise);
}

std::vector<double> CrossEntropySampler::calc_final_log_weights(const Deviation* g) const {
  std::vector<double> w(final_margins_.size());
  std::vector<double> z(static_cast<std::size_t>(opt_.dims));
  for (std::size_t k = 0; k < w.size(); ++k) w[k] = calc_point(opt_, final_, static_cast<std::int64_t>(k), z.data(), g);
  return w;
}

}  // namespace truss::sampling
