// subset_simulation.hpp — subset simulation (Au & Beck 2001) as a round-based state machine: pure
// mathematics, no I/O, no MPI. The evaluation engine drives it: it asks for the points of the next
// round, evaluates their margins (anywhere, on any rank), and hands the margins back in the
// round's order; the machine then plans the next round, until it says it is done.
//
// The failure event is {margin <= 0} (a margin is positive when safe, in its own unit). The inputs
// live in the standard normal space of the campaign's sampling dimensions: a point is z in R^d and
// its uniforms u_j = Phi(z_j) feed the dispersions' quantile functions (sampling.hpp), so the
// method never sees a distribution.
//
// Method (S.-K. Au, J. L. Beck, "Estimation of small failure probabilities in high dimensions by
// subset simulation", Probabilistic Engineering Mechanics 16 (2001) 263-277):
//   level 0      N independent standard normal points (one round).
//   threshold    after level k: sort its N margins; b_{k+1} = the N_c-th smallest
//                (N_c = p0 N; Hyndman-Fan type 1, so exactly N_c samples lie in
//                F_{k+1} = {margin <= b_{k+1}} when no margins tie). If b_{k+1} <= 0 the last level
//                is k: P_k = #{margin <= 0} / N. Otherwise P_k = #{margin <= b_{k+1}} / N (= p0
//                without ties) and level k + 1 samples F_{k+1}.
//   chains       the N_c samples with the smallest margins (ties by sample order) seed N_c
//                Markov chains; chain c has L_c = floor(N / N_c) states (one more for c < N mod N_c),
//                its seed being the first, so level k + 1 again holds N samples.
//   step         modified Metropolis (Au & Beck sec. 3.1): per dimension j, a candidate
//                e_j = z_j + a (2 U - 1) (uniform proposal of half-width a, symmetric) is kept
//                with probability min(1, phi(e_j) / phi(z_j)), else xi_j = z_j. If xi = z no
//                evaluation is needed (the chain repeats its state); otherwise xi is evaluated
//                and becomes the next state when its margin <= b_{k+1}, else the chain repeats.
//                One round = one step of every chain that still has states to make.
//   adaptive     adaptive conditional sampling (I. Papaioannou, W. Betz, K. Zwirglmaier, D. Straub,
//   step         "MCMC algorithms for subset simulation", Probabilistic Engineering Mechanics 41
//                (2015) 83-103, sec. 5, the aCS algorithm): the candidate is drawn as a whole,
//                v_j = rho_j z_j + sigma_j n_j, n_j standard normal, rho_j = sqrt(1 - sigma_j^2),
//                a proposal reversible with respect to the standard normal itself, so v is kept
//                exactly when its margin <= b_{k+1} (no per-dimension acceptance; every step is
//                evaluated). sigma_j = min(1, lambda sigma0_j), sigma0_j the sample standard
//                deviation of the level's seeds in dimension j (n - 1 in the denominator; 1 with
//                a single seed). The scale lambda starts at 0.6 (level 1) and is adapted towards
//                the acceptance rate a* = 0.44: after step i of a level (its round), with a_i the
//                share of that step's candidates kept, ln lambda += (a_i - a*) / sqrt(i); a level
//                starts with the previous level's last lambda. Papaioannou et al. adapt after each
//                group of chains run through; here a group is one step of every chain, so the
//                chains of a round run side by side and the adaptation is a function of the
//                round's counts (integers: never of the order results arrive in). Each step's
//                kernel leaves the conditional law invariant; that its lambda depends on the
//                previous steps of all N_c chains is an O(1/N_c) effect, like the estimator's
//                own bias.
//   estimate     p = prod_k P_k = p0^(m-1) P_m without ties (m levels).
//   CoV          delta_k^2 = (1 - P_k) / (N P_k) (1 + gamma_k) (Au & Beck eq. 29), gamma_0 = 0,
//                gamma_k = 2 sum_{l>=1} (n_l / N) rho_l (eq. 27), n_l the pairs of states l
//                steps apart in one chain (N - l N_c for equal chains), rho_l = R_l / R_0 with
//                R_l = (sum over those pairs of I I') / n_l - P_k^2 (eq. 28), R_0 = P_k (1 - P_k),
//                I = 1{margin <= threshold of the level}. delta^2 = sum_k delta_k^2 (the levels
//                taken as uncorrelated, as Au & Beck and OpenTURNS do).
//   lineage CoV  Au & Beck's delta counts the correlation along a chain but takes the levels (and
//                chains) as independent; they are not: a level's seeds are states of the previous
//                level's chains, so an excursion of one chain feeds several levels (on the linear
//                case delta is 0.7-0.85 of the spread over seeds, in OpenTURNS' SubsetSampling as
//                here). So the summary also gives the ancestral estimator of the SMC literature
//                (H. P. Chan, T. L. Lai, "A general theory of particle filters in hidden Markov
//                models and some applications", Ann. Statist. 41 (2013) 2877-2904; A. Lee,
//                N. Whiteley, "Variance estimation in the particle filter", Biometrika 105 (2018)
//                609-625): every sample has a root, the level-0 sample it descends from (a seed
//                keeps its root, a Markov state its chain's); to first order
//                ln p^ - ln p = sum_k sum_i (I_ki - P_k) / (N P_k), and samples of different roots
//                are taken as independent, those of one root as arbitrarily dependent, within a
//                level and across levels: cov_lineage^2 = sum_r (sum_{k, i: root r}
//                (I_ki - P_k) / (N P_k))^2. It needs many surviving roots (SubsetSummary::lineages).
//   bound CoV    the CoV the intervals use: cov_bound = max(sum_k delta_k, cov_lineage). sum_k delta_k
//                is Au & Beck's bound for fully correlated levels (delta^2 <= sum_{i,j}
//                delta_i delta_j); cov_lineage alone under-covers when the failure samples descend
//                from few roots (a limit state governed by one or two inputs: its variance is then
//                estimated from a handful of independent groups and is too often too small).
//                Measured coverage: docs/campaigns.md "Which CoV to read".
//   lag CoV      the lineage estimate with a shorter memory (the fixed-lag idea of J. Olsson,
//                R. Douc, "Numerically stable online estimation of variance in particle filters",
//                Bernoulli 25 (2019) 1504-1535): a unit is a chain (at level 0 a sample); every
//                unit of level k >= 1 has a parent, the unit of level k - 1 its seed belongs to.
//                With T_k(u) the sum of (I - P_k) / (N P_k) over unit u's samples, the covariance
//                of levels k <= j is estimated by grouping both levels' units by their ancestor at
//                level g = max(0, k - lag): C_kj = sum_a T_k(a) T_j(a), and
//                cov_lag^2 = sum_k C_kk + 2 sum_{k<j} C_kj. lag = 0 counts the correlation along
//                each chain (Au & Beck's gamma, per chain); lag 1 also that of chains sharing a
//                parent and of each level with the levels that descend from it; unbounded lag is
//                cov_lineage. Lags of 1 and more agree in the mean (measured on the analytic cases:
//                root mean squares within 2 % of cov_lineage's), lag 1 from many more groups.
//   interval CoV the CoV of the intervals (cov_interval), in s = sqrt(ln(1 + cov^2)) of ln p^:
//                s^2 = (G s_1^2 + 2 s_b^2) / (G + 2), s_1 from the lag-1 CoV, s_b from cov_bound,
//                G = lineage_groups. With many independent lineages (G large) the lag-1 estimate
//                is close to the spread over seeds; with few it is biased low (to 0.5 of the
//                spread at N = 500, p = 1e-7, where G is about 2), and the interval leans on the
//                conservative bound, weighted as two lineages' worth. Measured coverage and width
//                against cov_bound's: bench/subset_coverage.py, docs/benchmarks.md.
//   beta         -Phi^-1(p).
// Random numbers are keyed by (master seed, level, chain, step, dimension, stream) with the
// counter-based generator of sampling.hpp: never by rank or arrival order. Level 0's point k is
// the chain index k, step 0. So a run's point is a pure function of the round's plan (the bytes
// of SubsetRound::encode) and its index in the round, on any rank, and after a resume.
//
// Margins that are NaN (a run that could not say) count as safe at every level (+infinity) and
// are counted (SubsetLevel::unusable); the caller decides which statuses give which margin.
// A Markov chain repeats its state when it rejects, so a level holds repeated margins: its count
// #{margin <= threshold} may exceed N_c (SubsetLevel::ties) and P_k is then that count over N.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace truss::sampling {

// How a Markov step proposes its candidate ("step" and "adaptive step" above).
enum class SubsetProposal { modified_metropolis, adaptive_conditional };
inline constexpr const char* kSubsetProposalNames[] = {"modified_metropolis", "adaptive_conditional"};
inline const char* to_string(SubsetProposal p) { return kSubsetProposalNames[static_cast<int>(p)]; }

// Which CoV a campaign's lognormal interval uses: cov_bound or cov_interval ("bound CoV" and
// "interval CoV" above; SubsetSummary::calc_interval_cov).
enum class SubsetIntervalCov { cov_bound, cov_interval };
inline constexpr const char* kSubsetIntervalCovNames[] = {"cov_bound", "cov_interval"};
inline const char* to_string(SubsetIntervalCov c) { return kSubsetIntervalCovNames[static_cast<int>(c)]; }

struct SubsetOptions {
  int dims = 0;                      // standard normal dimensions of a point (the campaign's d)
  SubsetProposal proposal = SubsetProposal::modified_metropolis;
  std::int64_t n_per_level = 2000;   // N: samples per level
  double p0 = 0.1;                   // conditional probability per level, in (0, 0.5]
  int max_levels = 20;               // levels including level 0; the estimate stops there
  double proposal_half_width = 1.0;  // a: uniform proposal on [z - a, z + a] (width 2, as Au & Beck), in
                                     // [kMinProposalHalfWidth, kMaxProposalHalfWidth]
  // The range of a (standard deviations): below it steps are lost in the rounding of z, above it
  // nearly every candidate lies where phi is negligible; outside it the chains stand still.
  static constexpr double kMinProposalHalfWidth = 1e-3, kMaxProposalHalfWidth = 10.0;
  // Adaptive conditional sampling: the first lambda and the acceptance rate it is adapted to
  // (Papaioannou et al. 2015, sec. 5: 0.44, the optimum of a one-dimensional random walk).
  static constexpr double kInitialScale = 0.6, kTargetAcceptance = 0.44;
  std::uint64_t seed = 0;            // master seed of the campaign

  // "" when usable, else "field: reason". N p0 must be a whole number of chains N_c >= 1.
  std::string validate() const;
  std::int64_t n_chains() const;        // N_c = p0 N (valid options only)
  std::int64_t max_evaluations() const;  // N + (max_levels - 1) (N - N_c): the cap on runs
};

// The points of one round: what every rank needs to compute a point (rank 0 plans it and
// broadcasts encode()).
struct SubsetRound {
  std::int64_t index = 0;     // round number, 0 = level 0
  std::int64_t first_evaluation = 0;  // evaluations proposed before this round (run ordinal of point 0)
  int level = 0;
  int step = 0;               // Markov step (>= 1); 0 for level 0
  double threshold = std::numeric_limits<double>::infinity();  // a candidate is accepted when its margin <= this
  std::int64_t n_points = 0;
  std::vector<std::int64_t> chains;  // step >= 1: the chain of each point, ascending
  std::vector<double> z;             // step >= 1: the candidates, n_points x dims, row-major

  std::string encode() const;
  // Throws std::runtime_error for bytes that are not an encoded round of `dims` dimensions.
  static SubsetRound decode(std::string_view bytes, int dims);
};

// Point k (0 <= k < n_points) of a round: z in the standard normal space, and u = Phi(z) inside
// (0, 1) (level 0: the keyed uniforms themselves). Pure; throws std::out_of_range for a bad k.
void calc_round_normals(const SubsetOptions& o, const SubsetRound& r, std::int64_t k, double* z);
void calc_round_uniforms(const SubsetOptions& o, const SubsetRound& r, std::int64_t k, double* u);

struct SubsetLevel {
  double threshold = 0.0;      // b_{k+1}: the level's estimate counts margin <= this (0 at the last level)
  double probability = 0.0;    // P_k: conditional probability estimated by this level
  double gamma = 0.0;          // chain correlation factor (0 at level 0)
  double cov = 0.0;            // delta_k
  std::int64_t runs = 0;       // evaluations made for this level's samples
  std::int64_t steps = 0;      // Markov steps (N - N_c at level >= 1)
  std::int64_t moved = 0;      // steps whose new state differs from the old
  std::int64_t unusable = 0;   // of those runs, the ones whose margin was NaN
  std::int64_t ties = 0;       // samples at the threshold beyond the N_c-th (repeated states, plateaus)
  double scale = std::numeric_limits<double>::quiet_NaN();  // adaptive: lambda after the level's last step
  double acceptance() const {  // moved / steps (NaN at level 0)
    if (steps == 0) return std::numeric_limits<double>::quiet_NaN();
    return static_cast<double>(moved) / static_cast<double>(steps);
  }
};

// chains_stuck: a level >= 1 whose Markov chains never moved (acceptance 0): its samples only
// repeat its seeds, so there is no estimate (p and beta NaN).
enum class SubsetStatus { running, converged, level_cap, no_progress, chains_stuck };
inline constexpr const char* kSubsetStatusNames[] = {"running",     "converged",   "level_cap",
                                                     "no_progress", "chains_stuck"};
inline const char* to_string(SubsetStatus s) { return kSubsetStatusNames[static_cast<int>(s)]; }

struct SubsetSummary {
  SubsetStatus status = SubsetStatus::running;
  std::string message;
  double p = std::numeric_limits<double>::quiet_NaN();     // failure probability estimate
  double cov = std::numeric_limits<double>::quiet_NaN();   // its coefficient of variation (Au & Beck)
  double cov_lineage = std::numeric_limits<double>::quiet_NaN();  // the ancestral estimate (see above)
  double cov_bound = std::numeric_limits<double>::quiet_NaN();  // the full-correlation bound (see above)
  double cov_lag1 = std::numeric_limits<double>::quiet_NaN();   // the lag CoV at lag 1 (see above)
  double cov_interval = std::numeric_limits<double>::quiet_NaN();  // the CoV of the intervals (see above)
  std::int64_t lineages = 0;  // distinct roots among the last level's samples
  // The lineage estimate's effective number of independent groups, (sum_r x_r^2)^2 / sum_r x_r^4 over
  // the roots' terms x_r (Kish): the degrees of freedom its variance rests on, plus one.
  double lineage_groups = 0.0;
  double beta = std::numeric_limits<double>::quiet_NaN();  // -Phi^-1(p)
  std::int64_t runs = 0;     // evaluations
  std::int64_t rounds = 0;   // rounds completed
  std::vector<SubsetLevel> levels;
  // The CoV the rule names (cov_bound or cov_interval).
  double calc_interval_cov(SubsetIntervalCov rule) const {
    return rule == SubsetIntervalCov::cov_interval ? cov_interval : cov_bound;
  }
  // Crude Monte Carlo runs for the same CoV: (1 - p) / (p cov^2).
  double calc_crude_runs() const { return (1.0 - p) / (p * cov * cov); }
  // Levels "on a plateau" of the margin: thresholds b_k > 0 with b_k - b_{k+1} < kPlateauShare b_k.
  // On a plateau the margin hardly depends on the inputs that lead to the failure: the levels select
  // on others, each still multiplies p by about p0, and the estimate can lie far below p, beyond what
  // any CoV says (docs/sweep-tolerance-allocation.md: 1.5e-13 where p is about 6e-8).
  int calc_plateau_levels() const;
  static constexpr double kPlateauShare = 0.01;
  static constexpr int kPlateauLevels = 3;  // from this many on, the estimate is not trusted
};

// Why an estimate must not feed an allowable ("" when it may): not finished, no estimate
// (chains_stuck), no progress (the last level's share, not the failure's), kPlateauLevels or more
// plateau levels. A level cap stands: the failure lies beyond the last threshold, so the last
// level's share bounds p from above (P(F) <= P(g <= b_L)), the safe side of p <= p_target.
std::string find_untrusted_reason(const SubsetSummary& s);

// A failing sample of the last level: its evaluation ordinal (the run ordinal: rounds number
// their points consecutively), its margin, and z.
struct SubsetSample {
  std::int64_t evaluation = 0;
  double margin = 0.0;
  std::vector<double> z;
};

class SubsetSimulation {
 public:
  // Throws std::invalid_argument with validate()'s message for unusable options.
  explicit SubsetSimulation(const SubsetOptions& o);

  bool done() const { return status_ != SubsetStatus::running; }
  // The round to evaluate next (only while !done()).
  const SubsetRound& round() const { return round_; }
  // The margins of round()'s points, in its order. Plans the next round (or finishes). Throws
  // std::logic_error when done, std::invalid_argument for a wrong count.
  void add_margins(std::span<const double> margins);

  SubsetSummary calc_summary() const;
  // The distinct evaluated points of the last level with margin <= 0, by evaluation (when done).
  std::vector<SubsetSample> calc_failure_samples() const;
  const SubsetOptions& options() const { return opt_; }
  // The CoV of ln p^ with the samples grouped by their ancestors `lag` levels up (see "lag CoV";
  // lag < 0: by their roots, the lineage CoV).
  double calc_lag_cov(int lag) const;

  // The whole state, bit for bit (a resume may load it instead of replaying the rounds).
  std::string save() const;
  static SubsetSimulation load(std::string_view bytes);  // throws std::runtime_error if malformed

 private:
  struct Sample {
    double margin;
    std::int64_t chain, step, evaluation;
    std::int64_t root;  // the level-0 sample it descends from
  };
  SubsetSimulation() = default;
  void take_level0(std::span<const double> margins);
  void take_step(std::span<const double> margins);
  void push_sample(const Sample& s, const double* z);
  void advance(int done_step);
  void finish_level();
  void start_level(double threshold, const std::vector<std::int64_t>& seeds);
  void plan_step(int step);
  void adapt_scale(int step, std::int64_t evaluated, std::int64_t kept);
  void calc_seed_spread();
  double calc_gamma(double threshold, double p) const;
  void add_lineage(double threshold, double p);
  std::vector<double> calc_terms_at(std::size_t k, std::size_t g) const;
  std::int64_t chain_length(std::int64_t c) const;

  SubsetOptions opt_;
  SubsetStatus status_ = SubsetStatus::running;
  std::string message_;
  SubsetRound round_;
  std::int64_t evaluations_ = 0;      // points proposed in completed rounds
  std::int64_t rounds_ = 0;           // completed rounds
  double domain_ = std::numeric_limits<double>::infinity();  // threshold of the level being sampled
  std::vector<Sample> samples_;       // the level being sampled, in order of creation
  std::vector<double> z_;             // their points, samples_.size() x dims
  std::vector<std::int64_t> head_;    // per chain: its latest sample
  std::vector<SubsetLevel> levels_;   // finished levels, and the current one last
  std::vector<double> lineage_;       // per root: sum over its finished-level samples of (I - P_k) / (N P_k)
  std::vector<std::vector<double>> unit_terms_;  // per finished level, per unit: the sum of its (I - P_k) / (N P_k)
  std::vector<std::vector<std::int64_t>> parents_;  // per level >= 1, per chain: its seed's unit at the level before
  double scale_ = SubsetOptions::kInitialScale;  // adaptive: lambda of the next step
  std::vector<double> spread0_;       // adaptive: sigma0_j of the current level's seeds
};

}  // namespace truss::sampling
