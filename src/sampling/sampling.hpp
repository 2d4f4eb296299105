// sampling.hpp — reproducible sampling for MPI uncertainty campaigns.
//
// What lives here (namespace truss::sampling):
//   * a counter-based generator: every uniform is a pure function of
//     (master_seed, run_index, dimension_index, extra), so a campaign gives the
//     same inputs whatever the MPI rank count and whatever order runs are
//     computed in;
//   * input distributions given by their inverse CDF (calc_quantile), so that
//     every sampling plan (Monte Carlo, Latin hypercube, Sobol', Saltelli)
//     produces uniforms and the distributions map them to values;
//   * SamplePlan: the uniforms of run i for methods monte_carlo,
//     latin_hypercube, sobol and saltelli, each O(d) (Sobol' O(d log n)) per
//     run, without materialising the whole design;
//   * calc_sobol_indices: first-order and total Sobol' indices from the
//     outputs of a Saltelli plan, with block-bootstrap confidence intervals.
//
// This library depends on nothing else in the project (fmt only, for messages).
//
// Sources of the algorithms (details at each definition in sampling.cpp):
//   - SplitMix64 finaliser: G. Steele, D. Lea, C. Flood, "Fast splittable
//     pseudorandom number generators", OOPSLA 2014; mixing constants of
//     D. Stafford's "Mix13" variant.
//   - Normal quantile: M. J. Wichura, "Algorithm AS 241: The percentage points
//     of the normal distribution", Applied Statistics 37 (1988) 477-484.
//   - Keyed permutation: M. Luby, C. Rackoff, "How to construct pseudorandom
//     permutations from pseudorandom functions", SIAM J. Comput. 17 (1988);
//     cycle walking: J. Black, P. Rogaway, "Ciphers with arbitrary finite
//     domains", CT-RSA 2002.
//   - Sobol' sequence: I. M. Sobol', USSR Comput. Math. Math. Phys. 7 (1967);
//     direction numbers S. Joe, F. Y. Kuo, "Constructing Sobol sequences with
//     better two-dimensional projections", SIAM J. Sci. Comput. 30 (2008)
//     2635-2654, file new-joe-kuo-6.21201 (see sobol_directions.inc).
//   - Saltelli design and estimators: A. Saltelli et al., "Variance based
//     sensitivity analysis of model output. Design and estimator for the total
//     sensitivity index", Comput. Phys. Commun. 181 (2010) 259-270: the
//     A, B, AB_i design and, from their Table 2, the first-order estimator
//     V_i ~ mean f(B) (f(AB_i) - f(A)) and Jansen's (1999) total-effect
//     estimator E_~i ~ mean (f(A) - f(AB_i))^2 / 2.
//
// Bitwise reproducibility: the path from a key to a uniform uses only 64-bit
// integer arithmetic and one exact multiplication by a power of two, so it is
// identical on every IEEE-754 machine. Quantiles additionally use log, exp,
// sqrt and erfc from <cmath>: identical for a given libm, possibly one ulp
// apart across different libm implementations. sampling.cpp is compiled with
// -ffp-contract=off so that no compiler fuses multiply-adds differently on
// machines with FMA.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace truss::sampling {

// ---------------------------------------------------------------------------
// Counter-based generator
// ---------------------------------------------------------------------------

// Stafford "Mix13" finaliser of SplitMix64: a bijection of 64-bit words with
// full avalanche.
constexpr std::uint64_t mix64(std::uint64_t z) noexcept {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Odd Weyl increment of SplitMix64 (2^64 / golden ratio).
inline constexpr std::uint64_t kGoldenGamma = 0x9e3779b97f4a7c15ULL;

// One SplitMix64 step: the output at position `counter` of the stream whose
// state is `state`. Each level of the key hash below is such a step, so keys
// that differ in one component land in statistically independent streams.
constexpr std::uint64_t splitmix_at(std::uint64_t state, std::uint64_t counter) noexcept {
  return mix64(state + (counter + 1) * kGoldenGamma);
}

// Stream tags ("extra") reserved by this library; callers that need their own
// streams should use small values of `extra` (0 is what Monte Carlo uses, so
// counter_uniform(seed, run, dim) is exactly the monte_carlo plan's value).
inline constexpr std::uint64_t kTagMonteCarlo = 0;
inline constexpr std::uint64_t kTagLhsJitter = 0x4c48532d4a495454ULL;   // "LHS-JITT"
inline constexpr std::uint64_t kTagLhsPerm = 0x4c48532d5045524dULL;     // "LHS-PERM"
inline constexpr std::uint64_t kTagSobolShift = 0x534f424f4c2d5348ULL;  // "SOBOL-SH"
inline constexpr std::uint64_t kTagBootstrap = 0x424f4f5453545250ULL;   // "BOOTSTRP"

// Hash of the part of the key that is common to all dimensions of one run;
// exposed so that callers filling many dimensions hash the prefix once.
constexpr std::uint64_t counter_run_state(std::uint64_t master_seed, std::int64_t run_index,
                                          std::uint64_t extra = 0) noexcept {
  const std::uint64_t s0 = mix64(master_seed ^ 0x6a09e667f3bcc909ULL);
  const std::uint64_t s1 = splitmix_at(s0, extra);
  return splitmix_at(s1, static_cast<std::uint64_t>(run_index));
}

// 64 random bits for the key (master_seed, run_index, dimension_index, extra).
constexpr std::uint64_t counter_hash(std::uint64_t master_seed, std::int64_t run_index,
                                     std::int64_t dimension_index, std::uint64_t extra = 0) noexcept {
  return splitmix_at(counter_run_state(master_seed, run_index, extra),
                     static_cast<std::uint64_t>(dimension_index));
}

// Uniform in the open interval (0, 1) from the top 53 bits k of `bits`:
// u = k * 2^-53, exact in binary64; k = 0 (probability 2^-53) is sent to
// 2^-54 so that no value is exactly 0. The largest value is 1 - 2^-53.
// (The textbook (k + 0.5) * 2^-53 is not exact for k >= 2^52 and rounds the
// top value up to 1.0.)
constexpr double to_open_unit(std::uint64_t bits) noexcept {
  const std::uint64_t k = bits >> 11;
  return k != 0 ? static_cast<double>(k) * 0x1p-53 : 0x1p-54;
}

constexpr double counter_uniform(std::uint64_t master_seed, std::int64_t run_index,
                                 std::int64_t dimension_index, std::uint64_t extra = 0) noexcept {
  return to_open_unit(counter_hash(master_seed, run_index, dimension_index, extra));
}

// ---------------------------------------------------------------------------
// Standard normal
// ---------------------------------------------------------------------------

// Phi(x) = erfc(-x / sqrt 2) / 2; accurate relative to Phi in the lower tail
// (down to Phi ~ 1e-308), absolutely near 1.
double normal_cdf(double x);

// Phi^-1(p) by Wichura's AS 241 (PPND16), relative accuracy ~1e-16 for
// 1e-300 < min(p, 1-p). Returns -inf at 0, +inf at 1, NaN outside [0, 1].
double normal_quantile(double p);
// z[i] = normal_quantile(p[i]) for i < count, bit for bit (p and z may be the same array): the
// central region |p - 0.5| <= 0.425 in one vectorised pass, the tails one at a time.
void normal_quantiles(const double* p, double* z, std::size_t count);

// Phi(z) kept inside the open interval the quantile functions take, [2^-54, 1 - 2^-53] (the ends of
// to_open_unit): a point of the standard normal space as the uniforms a run's draws read.
inline double calc_open_normal_cdf(double z) { return std::clamp(normal_cdf(z), 0x1p-54, 1.0 - 0x1p-53); }

// ---------------------------------------------------------------------------
// Distributions
// ---------------------------------------------------------------------------

enum class DistributionKind { normal, truncated_normal, uniform, lognormal, discrete };
// Names as campaign files write them, in enum order.
inline constexpr const char* kDistributionNames[] = {"normal", "truncated_normal", "uniform", "lognormal", "discrete"};
inline const char* to_string(DistributionKind k) { return kDistributionNames[static_cast<int>(k)]; }

// One uncertain input. Fields that a kind does not use are ignored; build with
// the static factories. calc_quantile() requires validate() to be empty.
struct Distribution {
  DistributionKind kind = DistributionKind::normal;

  // normal, truncated_normal: parameters of the parent normal.
  double mean = 0.0;
  double std = 1.0;
  // truncated_normal: truncation interval (infinite bounds allowed);
  // uniform: support (finite).
  double lower = 0.0;
  double upper = 1.0;
  // lognormal: X = exp(Y), Y ~ normal(mu, sigma). mu = log(median of X),
  // sigma = standard deviation of log X (not of X).
  double mu = 0.0;
  double sigma = 1.0;
  // discrete: values strictly increasing (the factory sorts them), weights
  // positive, same length; weights need not sum to 1.
  std::vector<double> values;
  std::vector<double> weights;

  static Distribution normal(double mean, double std);
  static Distribution truncated_normal(double mean, double std, double lower, double upper);
  static Distribution uniform(double lower, double upper);
  // Parameters of the underlying normal: median of X is exp(mu).
  static Distribution lognormal(double mu, double sigma);
  // Same, given the median of X instead of mu.
  static Distribution lognormal_from_median(double median, double sigma);
  // Sorts (value, weight) pairs by value when the lengths agree.
  static Distribution discrete(std::vector<double> values, std::vector<double> weights);

  // "" when usable, else "field: reason".
  std::string validate() const;

  // ln f(x), the log density (-inf outside the support); NaN for discrete (no density).
  double calc_log_density(double x) const;
  // Inverse CDF: the value x with F(x) = u, for u in (0, 1). For discrete,
  // the smallest value whose cumulative (normalised) weight is >= u.
  double calc_quantile(double u) const;
  // The normal score of x: Phi^-1(F(x)), the point of the standard normal space whose quantile is x
  // (the inverse of calc_quantile(Phi(z)); computed from the tail x lies in); NaN for discrete.
  double calc_normal_score(double x) const;
  // x[i] = calc_quantile(u[i]) for i < count, the same bits, in bulk (a per-bay dispersion's draws):
  // the kind is looked at once, and the normal quantile's central region is computed for all i
  // side by side, which the core overlaps (and vectorises) where one call at a time waits on its
  // division. u and x may be the same array.
  void calc_quantiles(const double* u, double* x, std::size_t count) const;
};

// ---------------------------------------------------------------------------
// Sampling plans
// ---------------------------------------------------------------------------

// How run i gets its d uniforms (all strictly inside (0, 1)):
//   monte_carlo      u_j = counter_uniform(seed, i, j).
//   latin_hypercube  u_j = (pi_j(i) + v_ij) / n, with pi_j a pseudorandom
//                    permutation of [0, n) that depends only on (seed, j) —
//                    a 6-round Feistel network on the smallest power of two
//                    >= n (at least 4) with cycle walking, evaluated
//                    at i without materialising it — and v_ij a
//                    counter-based jitter. Each dimension has exactly one
//                    sample per stratum [k/n, (k+1)/n).
//   sobol            point i of the Joe-Kuo Sobol' sequence (Gray-code
//                    order) in d dimensions, with a random digital shift:
//                    each coordinate's 53 binary digits are XORed with a
//                    seed-keyed mask whose last digit is 1, so no value is 0
//                    or 1. The first point (index 0) is NOT skipped: under
//                    the shift it is an ordinary random point, and skipping
//                    it would break the property that every block of 2^m
//                    consecutive points has one point in each dyadic interval
//                    of length 2^-m (A. B. Owen, "On dropping the first Sobol'
//                    point", MCQMC 2020, arXiv:2008.08051).
//   saltelli         blocks of G + 2 runs: A, B, AB_1 .. AB_G for G factors.
//                    Block b's base point is point b of the plain
//                    2d-dimensional sobol plan (shifted Sobol', same seed) if
//                    2d <= kSaltelliSobolMaxDims, else of the plain
//                    monte_carlo plan (counter_uniform(seed, b, j)): A = its
//                    first d coordinates, B = the last d. A factor is a group
//                    of consecutive dimensions (by default each dimension is
//                    its own factor, G = d); AB_g = A with every dimension of
//                    factor g taken from B.
enum class SamplingMethod { monte_carlo, latin_hypercube, sobol, saltelli };
inline constexpr const char* kSamplingNames[] = {"monte_carlo", "latin_hypercube", "sobol", "saltelli"};
inline const char* to_string(SamplingMethod m) { return kSamplingNames[static_cast<int>(m)]; }

// Largest Sobol' dimension embedded (Joe-Kuo new-joe-kuo-6.21201 dimensions
// 1..kSobolMaxDims). Beyond it a sobol plan fails validation.
inline constexpr int kSobolMaxDims = 2048;

// Largest base dimension 2d of a saltelli plan whose A and B come from one
// Sobol' point; beyond it they come from the Monte Carlo generator. Saltelli's
// estimators need every column of A independent of the same column of B (and
// of the other columns): a correlation rho between A_j and B_j scales both
// indices of factor j by (1 - rho). In the Joe-Kuo sequence, many pairs of
// dimensions beyond the first few have the same first digit, as a linear
// function of the point index, over the first 2^m points: such a pair
// correlates by +-0.75 (next digits: +-0.19, +-0.05), e.g. dimensions 183 and
// 367 (rail.x_m of the Table-1 sensitivity campaign, d = 184) at N = 256. No
// scrambling fixes this: a digital shift, a linear (Matousek) or a nested
// (Owen) scramble flips digit k of a coordinate by a function of its digits
// before k, the first digit by a constant, so two coordinates with tied first
// digits stay tied (only the sign of the correlation becomes random; a nested
// scramble of dimensions 183 and 367 gives +-0.75 at N = 256 for every seed). Within the first 8 dimensions every
// pair stays below 2 / sqrt(N) from N = 64 (4 / sqrt(N), the report's
// design-check bound, from N = 16; tests/unit/test_saltelli_design.cpp), so
// small designs keep the lower error of Sobol' points; the Monte Carlo base is unbiased at
// any d, and its bootstrap intervals are exact (its blocks are independent).
inline constexpr int kSaltelliSobolMaxDims = 8;

class SamplePlan {
 public:
  // n_runs: number of runs (for saltelli, N * (G + 2));
  // d: uniforms per run. Never throws for bad arguments: call validate().
  // saltelli_groups (saltelli only): sizes of the G factors, consecutive
  // groups of dimensions in order, each >= 1, summing to d (a campaign's
  // per-bay dispersion is one factor spanning all its bays). Empty: every
  // dimension is its own factor.
  SamplePlan(SamplingMethod method, std::int64_t n_runs, int d, std::uint64_t master_seed,
             std::vector<int> saltelli_groups = {});

  // "" when usable, else "field: reason".
  std::string validate() const;

  // u[0..d) for run run_index in [0, n_runs), all strictly inside (0, 1).
  // Pure and thread-safe. Throws std::logic_error if validate() is not
  // empty, std::out_of_range for a bad run index.
  void calc_uniforms(std::int64_t run_index, double* u) const;

  // x[j] = dists[j].calc_quantile(u[j]); dists.size() must be d
  // (std::invalid_argument otherwise). No allocation.
  void calc_values(std::int64_t run_index, std::span<const Distribution> dists, double* x) const;

  // Runs per Saltelli block of G factors: A, B, AB_1 .. AB_G.
  static int saltelli_block(int factors) { return factors + 2; }
  // saltelli: number of factors G (groups, or d without groups); otherwise 0.
  int saltelli_factors() const;

  // The raw (unshifted) Joe-Kuo Sobol' point: coordinate `dim` (0-based:
  // dim 0 is Joe-Kuo dimension 1) of point `index`, in Gray-code order, as
  // a 32-bit binary fraction in [0, 1). Index 0 is the origin.
  static double sobol_point_unshifted(std::uint32_t index, int dim);

  SamplingMethod method() const { return method_; }
  std::int64_t n_runs() const { return n_runs_; }
  int dims() const { return d_; }
  std::uint64_t master_seed() const { return seed_; }
  // saltelli: number of blocks N; otherwise 0.
  std::int64_t saltelli_base_count() const;
  // saltelli: whether the base sample is Sobol' (2d <= kSaltelliSobolMaxDims).
  bool saltelli_uses_sobol() const {
    return method_ == SamplingMethod::saltelli && 2 * d_ <= kSaltelliSobolMaxDims;
  }

 private:
  void calc_sobol(std::uint64_t index, int first, int count, std::uint32_t* x) const;
  void calc_latin_hypercube(std::int64_t run_index, double* u) const;
  std::string validate_groups() const;

  SamplingMethod method_;
  std::int64_t n_runs_;
  int d_;
  std::uint64_t seed_;
  // saltelli: factor g spans dimensions [group_begin_[g], group_begin_[g + 1]).
  std::vector<int> groups_;
  std::vector<int> group_begin_;
  bool valid_ = false;

  // latin_hypercube: Feistel network on feistel_bits_ bits, rounds keyed per dimension.
  int feistel_bits_ = 0;
  std::vector<std::uint64_t> round_keys_;  // [round * d + dim], plus kGoldenGamma

  // sobol / saltelli with Sobol' base: direction numbers laid out [bit][dim]
  // so that the XOR loop over dimensions is contiguous, and the 53-bit
  // digital shift per dimension.
  int sobol_dims_ = 0;
  std::vector<std::uint32_t> directions_;
  std::vector<std::uint64_t> shifts_;
};

// ---------------------------------------------------------------------------
// Sobol' indices from a Saltelli plan
// ---------------------------------------------------------------------------

struct SobolIndices {
  int d = 0;
  std::int64_t n_base = 0;          // N blocks
  double mean = 0.0;                // of f(A) and f(B) together
  double variance = 0.0;            // V = population variance of f(A) and f(B) together
  std::vector<double> first_order;  // S_i
  std::vector<double> total;        // ST_i
  // Percentile bootstrap intervals (NaN when n_resamples == 0).
  int n_resamples = 0;
  double confidence = 0.0;
  std::vector<double> first_order_lo, first_order_hi;
  std::vector<double> total_lo, total_hi;
};

// y: outputs of the runs of a saltelli plan, in run order (blocks of d + 2:
// f(A), f(B), f(AB_1) .. f(AB_d)). Bootstrap resamples the N blocks with
// replacement, drawing from the counter-based generator keyed by
// bootstrap_seed, so the intervals are reproducible.
// Throws std::invalid_argument for a size that is not a multiple of d + 2,
// fewer than 2 blocks, non-finite outputs, or confidence outside (0, 1).
// A constant output (V = 0) gives NaN indices.
SobolIndices calc_sobol_indices(std::span<const double> y, int d, std::uint64_t bootstrap_seed,
                                int n_resamples = 1000, double confidence = 0.95);

}  // namespace truss::sampling
