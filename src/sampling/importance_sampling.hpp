// importance_sampling.hpp — cross-entropy importance sampling of a failure probability as a
// round-based state machine, like subset_simulation.hpp: pure mathematics, no I/O, no MPI. The
// engine asks for a round's points, evaluates their margins anywhere, and hands them back in the
// round's order; the machine adapts its sampling density, then draws the final runs the estimate
// rests on.
//
// The failure event is {margin <= 0}; NaN margins (runs that cannot say) count as safe. Points live
// in the standard normal space of the campaign's sampling dimensions (u = Phi(z) feeds the
// dispersions' quantile functions), where the campaign's own law is phi, the d-dimensional standard
// normal density.
//
// Method: the cross-entropy method (R. Y. Rubinstein, "Optimization of computer simulation models
// with rare events", European Journal of Operational Research 99 (1997) 89-112; its use for
// reliability in the standard normal space: N. Kurtz, J. Song, "Cross-entropy-based adaptive
// importance sampling using Gaussian mixture", Structural Safety 42 (2013) 35-44), with one Gaussian
// density of unit covariance h = N(mu, I) (the design-point density):
//   level t      n_per_level points from h_t (h_0 = phi); gamma_t = max(0, the margin quantile of
//                share rho: the ceil(rho n)-th smallest margin).
//   update       W_i = 1{margin_i <= gamma_t} f(z_i) / h_t(z_i), f the law the estimate is for
//                (phi, or phi times the caller's ratio: a mixture of the laws a sweep serves, so
//                the density covers all of them); the cross-entropy mean mu^ = sum W z / sum W.
//                Each component of mu moves to mu^_j only where mu^_j differs from it by more than
//                kSignificance (3) standard errors, se_j^2 = sum_i (W_i / sum W)^2 (z_ij - mu^_j)^2,
//                else keeps its value: of the hundred-odd dimensions of a campaign most do not lead
//                to the failure, and the elites' mean moves in each of them by noise of about
//                1 / sqrt(ESS); every such shift multiplies the weights' second moment by
//                exp(shift^2), and over 99 dimensions the weights degenerate (measured: one input
//                of 100 deciding, p = 1e-7: sd(ln p^) 6.7 with the plain mean, 0.06 filtered).
//                The covariance stays I: a full covariance estimated from a tail's elites
//                collapses within a few levels (its weights' ESS falls to 1), and a density of
//                unit covariance does not degenerate with the dimension.
//   stop         after the level whose gamma is 0 (its update is the final density); after
//                max_levels levels (level_cap) or a level whose gamma did not decrease
//                (no_progress) the final round is drawn from the last density all the same: its
//                estimate is unbiased whatever the density, and the estimate's own rule refuses it
//                where the weights degenerate (reweighting.hpp).
//   refusal      the mean's noise: each component's standard error when it last moved, summed as
//                E = sum_j se_j^2; a Gaussian shift off by delta multiplies the weights' second
//                moment by about exp(|delta|^2), so E is what the density's own noise costs. Above
//                kMaxMeanNoise (0.3: the second moment 1.35 times) the sampler refuses every law
//                (find_refusal): the noise then comes from many dimensions each moving a little (a
//                failure to which many inputs contribute), the filter keeps only the components whose
//                noise pushed them past it, and the estimates run low while their weights look sound
//                (measured: 30 inputs of equal weight, E = 0.47-0.93, intervals holding p in 83-90 %
//                of seeds; one input of 100 deciding, E <= 0.12, 92-95 %).
//   final        n_final points from the final density h; their margins and ln w = ln phi(z) -
//                ln h(z) = |mu|^2 / 2 - mu.z are the estimate's (calc_weighted_estimate; other laws
//                add their log ratio to ln w). The adaptation's runs do not enter it: the final
//                runs are independent draws of one fixed density, so the estimate is unbiased and
//                its sample variance honest.
//   final density  N(mu, I), or, given a Deviation g (law_mixture.hpp: a reweighted spread sweep), the
//                density h(z) = g(z - mu) of the final round alone: its point k is z = mu + n with
//                n = g's transport of the keyed normals and of one more keyed uniform (number
//                dims of the point's stream), and ln phi(z) - ln h(z) = |mu|^2 / 2 - mu.z -
//                ln g(n) / phi(n). The adaptation's levels always draw from N(mu, I).
// Random numbers: point k of a round is z = mu + n, n_j = Phi^-1(counter_uniform(seed, e, j,
// kTagImportance)), e = the round's first evaluation + k (the run ordinal): a pure function of the
// round's plan (its bytes: mu), the index and the Deviation (fixed by the campaign's options), on any
// rank and after a resume.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace truss::sampling {

inline constexpr std::uint64_t kTagImportance = 0x43452d494d505354ULL;  // "CE-IMPST"

struct ImportanceOptions {
  int dims = 0;
  std::int64_t n_per_level = 1000;  // points of each cross-entropy level
  std::int64_t n_final = 2000;      // points of the final round (the estimate's runs)
  double rho = 0.1;                 // elite share of a level, in (0, 0.5]
  int max_levels = 20;              // cross-entropy levels at most, in [1, 1000]
  static constexpr double kSignificance = 3.0;  // standard errors a mean component must move by
  static constexpr double kMaxMeanNoise = 0.3;   // the refusal (see above)
  std::uint64_t seed = 0;
  std::string validate() const;  // "" when usable, else "field: reason"
  std::int64_t max_evaluations() const { return max_levels * n_per_level + n_final; }
};

// A density g of the final round's deviation n = z - mu other than the standard normal phi.
class Deviation {
 public:
  virtual ~Deviation() = default;
  // n of a point from its keyed standard normals (in place, all dims) and its own keyed uniform
  // `pick` in (0, 1) (a mixture's choice of component).
  virtual void transport(double pick, double* n) const = 0;
  // ln g(n) - ln phi(n).
  virtual double calc_log_ratio(const double* n) const = 0;
};

// The points of one round: the density they are drawn from.
struct ImportanceRound {
  std::int64_t index = 0;
  std::int64_t first_evaluation = 0;
  int level = 0;          // cross-entropy level; the final round has level = the levels before it
  bool final = false;
  std::int64_t n_points = 0;
  std::vector<double> mean;      // mu (dims)
  std::string encode() const;
  static ImportanceRound decode(std::string_view bytes, int dims);  // throws std::runtime_error
};

// Point k of a round (z, and u = Phi(z) clamped inside (0, 1)); throws std::out_of_range for a bad k.
// `g`: the final round's deviation density (nullptr: N(0, I); ignored for the levels' rounds).
void calc_round_normals(const ImportanceOptions& o, const ImportanceRound& r, std::int64_t k, double* z,
                        const Deviation* g = nullptr);
void calc_round_uniforms(const ImportanceOptions& o, const ImportanceRound& r, std::int64_t k, double* u,
                         const Deviation* g = nullptr);
// ln phi(z) - ln h(z) of point k of a round.
double calc_round_log_weight(const ImportanceOptions& o, const ImportanceRound& r, std::int64_t k,
                             const Deviation* g = nullptr);

struct ImportanceLevel {
  double threshold = 0.0;       // gamma_t
  std::int64_t elites = 0;      // points with margin <= gamma_t
  std::int64_t runs = 0, unusable = 0;
  double elite_ess = 0.0;       // Kish's effective size of the update weights W
  double shift = 0.0;           // |mu| of the density the level drew from
  int moved = 0;                // mean components the update moved
  double mean_noise = 0.0;      // sum_j se_j^2 of the updated mean (each component's at its last move)
};

enum class ImportanceStatus { running, converged, level_cap, no_progress };
inline constexpr const char* kImportanceStatusNames[] = {"running", "converged", "level_cap", "no_progress"};
inline const char* to_string(ImportanceStatus s) { return kImportanceStatusNames[static_cast<int>(s)]; }

class CrossEntropySampler {
 public:
  explicit CrossEntropySampler(const ImportanceOptions& o);  // throws std::invalid_argument
  bool done() const { return done_; }
  const ImportanceRound& round() const { return round_; }
  // The margins of round()'s points, in its order; log_ratio (empty, or one per point, finite or
  // -inf): ln f / phi of the law the density adapts to (see "update"). Throws std::logic_error when done,
  // std::invalid_argument for wrong counts.
  void add_margins(std::span<const double> margins, std::span<const double> log_ratio = {});

  ImportanceStatus status() const { return status_; }  // how the adaptation ended (running until then)
  const std::string& message() const { return message_; }
  const std::vector<ImportanceLevel>& levels() const { return levels_; }
  std::int64_t runs() const { return evaluations_; }
  // The final round (when done): its plan, margins and ln phi / h per point.
  const ImportanceRound& final_round() const { return final_; }
  const std::vector<double>& final_margins() const { return final_margins_; }
  std::vector<double> calc_final_log_weights(const Deviation* g = nullptr) const;
  const ImportanceOptions& options() const { return opt_; }
  // Why no law's estimate may stand on these runs ("" when they may; see "refusal").
  std::string find_refusal() const;

 private:
  void take_level(std::span<const double> margins, std::span<const double> log_ratio);
  int update_mean(const std::vector<std::size_t>& elite, std::span<const double> log_ratio, double& ess);
  void plan(int level, bool final);
  ImportanceOptions opt_;
  bool done_ = false;
  ImportanceStatus status_ = ImportanceStatus::running;
  std::string message_;
  ImportanceRound round_, final_;
  std::int64_t evaluations_ = 0, rounds_ = 0;
  std::vector<double> mean_;      // the next round's density
  std::vector<double> mean_var_;  // per component: se^2 of its value (0 where never moved)
  std::vector<ImportanceLevel> levels_;
  std::vector<double> final_margins_;
};

}  // namespace truss::sampling
