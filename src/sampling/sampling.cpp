// sampling.cpp — sampling plans (distributions.cpp: distributions; sobol_indices.cpp: Sobol' indices) for
// uncertainty campaigns. See sampling.hpp for the API and the references; the
// comments here explain the choices that are not obvious from the code.
#include "sampling/sampling.hpp"
#include "sampling/simd_clones.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>


namespace truss::sampling {

namespace {

// Feistel rounds of the Latin hypercube permutation. Luby and Rackoff show 4
// rounds of a pseudorandom function give a strong pseudorandom permutation;
// 6 costs little and removes any visible structure for tiny domains (n < 16).
constexpr int kFeistelRounds = 6;

// Sobol' points are 32-bit binary fractions (enough for 2^32 runs); the
// digital shift is applied on 53 bits so the 21 low digits become random.
constexpr int kSobolBits = 32;

// ---------------------------------------------------------------------------
// Sobol' direction numbers (Joe & Kuo), expanded once to 32 bits per dimension.
// ---------------------------------------------------------------------------

constexpr std::uint16_t kJoeKuoRows[] = {
#include "sampling/sobol_directions.inc"
};

// Table [dim * 32 + k] = V_(k+1) of Joe-Kuo dimension dim + 1, scaled by 2^32.
const std::vector<std::uint32_t>& sobol_table() {
  static const std::vector<std::uint32_t> table = [] {
    std::vector<std::uint32_t> v(static_cast<std::size_t>(kSobolMaxDims) * kSobolBits);
    // Dimension 1: all m_k = 1, i.e. the van der Corput sequence.
    for (int k = 0; k < kSobolBits; ++k) v[static_cast<std::size_t>(k)] = 1u << (31 - k);
    std::size_t pos = 0;
    for (int dim = 1; dim < kSobolMaxDims; ++dim) {
      std::uint32_t* V = v.data() + static_cast<std::size_t>(dim) * kSobolBits - 1;  // V[1..32]
      const unsigned s = kJoeKuoRows[pos++];
      const unsigned a = kJoeKuoRows[pos++];
      for (unsigned i = 1; i <= s; ++i) V[i] = static_cast<std::uint32_t>(kJoeKuoRows[pos++]) << (32 - i);
      // Recurrence of Bratley & Fox (1988) in the form of Joe & Kuo's sobol.cc:
      // V_i = V_(i-s) ^ (V_(i-s) >> s) ^ XOR_k a_k V_(i-k).
      for (unsigned i = s + 1; i <= static_cast<unsigned>(kSobolBits); ++i) {
        V[i] = V[i - s] ^ (V[i - s] >> s);
        for (unsigned k = 1; k + 1 <= s; ++k)
          if ((a >> (s - 1 - k)) & 1u) V[i] ^= V[i - k];
      }
    }
    if (pos != std::size(kJoeKuoRows))
      throw std::logic_error("sobol_directions.inc: row count does not match kSobolMaxDims");
    return v;
  }();
  return table;
}

// Feistel network on `bits` bits (2 to 64), a bijection whatever the round function, here
// SplitMix64 keyed per round: x = (left, right) with right the low bits / 2 bits; a round maps
// (left, right) to (right, left ^ F(right)), so the halves swap widths each round when bits is odd
// (an unbalanced network; 6 rounds, an even number, restore the split). The domain 2^bits is the
// smallest power of two >= n, under 2n: cycle walking needs fewer than 2 applications on average
// (a balanced network on an even bit count would need up to 4).
// One application to x[0..k) (k <= kLanes), lane i keyed in round r by keys[r * stride + i]: the
// k hash chains are independent, so the core overlaps them instead of waiting on one chain at a
// time (a run's Latin hypercube point is hundreds of chains), and the lanes are contiguous so that
// the loop over them has no indirection. A key here is the round key plus kGoldenGamma:
// splitmix_at(key, x) = mix64(key + (x + 1) * gamma) = mix64((key + gamma) + x * gamma), one
// multiplication fewer per round.
constexpr int kLanes = 256;
TRUSS_SAMPLING_CLONES
void feistel_apply(std::uint64_t* x, int k, int bits, const std::uint64_t* keys, std::size_t stride) {
  auto mask = [](int b) { return b >= 64 ? ~0ULL : (1ULL << b) - 1; };
  int right_bits = bits / 2, left_bits = bits - right_bits;
  std::uint64_t left[kLanes], right[kLanes];
  for (int i = 0; i < k; ++i) {
    left[i] = x[i] >> right_bits;
    right[i] = x[i] & mask(right_bits);
  }
  for (int r = 0; r < kFeistelRounds; ++r) {
    const std::uint64_t m = mask(left_bits);  // F's output takes the left half's width
    const std::uint64_t* kr = keys + static_cast<std::size_t>(r) * stride;
    for (int i = 0; i < k; ++i) {
      const std::uint64_t f = mix64(kr[i] + right[i] * kGoldenGamma) & m;
      const std::uint64_t next = left[i] ^ f;
      left[i] = right[i];
      right[i] = next;
    }
    std::swap(left_bits, right_bits);
  }
  for (int i = 0; i < k; ++i) x[i] = (left[i] << right_bits) | right[i];
}

// u[l] = (s_l + v_l) / n for l < m: s_l = strata[l], v_l the counter-based jitter of dimension
// j0 + l (run state jitter_state), n = dn.
TRUSS_SAMPLING_CLONES
void place_in_strata(const std::uint64_t* strata, int m, std::uint64_t jitter_state, std::uint64_t j0, double dn,
                     double* u) {
  // Selections made on bit patterns (for doubles > 0 their order is the numbers' order) and both
  // arms computed: the loop has no branch and no floating-point comparison, so it vectorises.
  auto bits = [](double x) { return std::bit_cast<std::uint64_t>(x); };
  for (int l = 0; l < m; ++l) {
    const std::uint64_t k = splitmix_at(jitter_state, j0 + static_cast<std::uint64_t>(l)) >> 11;
    // to_open_unit(k << 11) without its branch: (2k + [k = 0]) 2^-54 is k 2^-53, or 2^-54 for
    // k = 0, exactly (2k < 2^54 is even).
    const auto twice = static_cast<std::int64_t>(2 * k + (k == 0));
    const double jitter = static_cast<double>(twice) * 0x1p-54;
    const double s = static_cast<double>(static_cast<std::int64_t>(strata[l]));  // < n <= 2^53: exact
    // s + jitter rounds up to s + 1 when jitter is within an ulp of 1; keep the sample inside its
    // stratum [s/n, (s+1)/n) and below 1: then the double just below hi (nextafter(hi, 0)).
    const std::uint64_t v = bits((s + jitter) / dn), hi = bits((s + 1.0) / dn);
    u[l] = std::bit_cast<double>(v >= hi ? hi - 1 : v);
  }
}

}  // namespace

// ===========================================================================
// SamplePlan
// ===========================================================================

SamplePlan::SamplePlan(SamplingMethod method, std::int64_t n_runs, int d, std::uint64_t master_seed,
                       std::vector<int> saltelli_groups)
    : method_(method), n_runs_(n_runs), d_(d), seed_(master_seed), groups_(std::move(saltelli_groups)) {
  valid_ = validate().empty();
  if (!valid_) return;
  if (method_ == SamplingMethod::saltelli) {
    if (groups_.empty()) groups_.assign(static_cast<std::size_t>(d_), 1);
    group_begin_.assign(1, 0);
    for (int size : groups_) group_begin_.push_back(group_begin_.back() + size);
  }

  const auto nd = static_cast<std::size_t>(d_);
  switch (method_) {
    case SamplingMethod::monte_carlo:
      break;
    case SamplingMethod::latin_hypercube: {
      // The smallest power of two >= n (at least 4, so that n = 2 is not the identity).
      feistel_bits_ = std::max(2, static_cast<int>(std::bit_width(static_cast<std::uint64_t>(n_runs_ - 1))));
      round_keys_.resize(nd * kFeistelRounds);
      // Round keys depend only on (seed, dimension): the permutation of a
      // dimension is fixed before any run is computed. Stored round-major, plus
      // kGoldenGamma, as feistel_apply reads them.
      for (std::size_t j = 0; j < nd; ++j)
        for (int r = 0; r < kFeistelRounds; ++r)
          round_keys_[static_cast<std::size_t>(r) * nd + j] =
              counter_hash(seed_, r, static_cast<std::int64_t>(j), kTagLhsPerm) + kGoldenGamma;
      break;
    }
    case SamplingMethod::sobol:
    case SamplingMethod::saltelli: {
      std::int64_t n_points = n_runs_;
      if (method_ == SamplingMethod::saltelli) {
        if (!saltelli_uses_sobol()) break;
        n_points = saltelli_base_count();
      }
      sobol_dims_ = (method_ == SamplingMethod::saltelli) ? 2 * d_ : d_;
      const auto ns = static_cast<std::size_t>(sobol_dims_);
      // Only the bits that Gray codes of indices < n_points can set.
      const int nbits =
          std::max(1, static_cast<int>(std::bit_width(static_cast<std::uint64_t>(n_points - 1))));
      const auto& table = sobol_table();
      directions_.resize(static_cast<std::size_t>(nbits) * ns);
      for (int k = 0; k < nbits; ++k)
        for (std::size_t j = 0; j < ns; ++j)
          directions_[static_cast<std::size_t>(k) * ns + j] =
              table[j * kSobolBits + static_cast<std::size_t>(k)];
      // Random digital shift (XOR) on 53 binary digits. Bit 0 is forced to
      // 1: unshifted points have zeros beyond digit 32, so every shifted
      // point is an odd multiple of 2^-53 and never exactly 0 (nor 1). The
      // shift is a bijection on each dyadic interval level, so the net
      // (stratification) properties of the first 32 digits are preserved.
      shifts_.resize(ns);
      for (std::size_t j = 0; j < ns; ++j)
        shifts_[j] = (counter_hash(seed_, 0, static_cast<std::int64_t>(j), kTagSobolShift) >> 11) | 1u;
      break;
    }
  }
}

int SamplePlan::saltelli_factors() const {
  if (method_ != SamplingMethod::saltelli) return 0;
  return groups_.empty() ? d_ : static_cast<int>(groups_.size());
}

std::int64_t SamplePlan::saltelli_base_count() const {
  if (method_ != SamplingMethod::saltelli || d_ < 1) return 0;
  return n_runs_ / saltelli_block(saltelli_factors());
}

std::string SamplePlan::validate() const {
  if (n_runs_ < 1) return fmt::format("n_runs: must be >= 1 (got {})", n_runs_);
  if (d_ < 0) return fmt::format("d: must be >= 0 (got {})", d_);
  if (!groups_.empty() && method_ != SamplingMethod::saltelli)
    return fmt::format("saltelli_groups: only a saltelli plan has factor groups (method {})", to_string(method_));
  switch (method_) {
    case SamplingMethod::monte_carlo:
      return {};
    case SamplingMethod::latin_hypercube:
      // Stratum indices must be exact in a double.
      if (n_runs_ > (std::int64_t{1} << 53))
        return fmt::format("n_runs: latin_hypercube supports at most 2^53 runs (got {})", n_runs_);
      return {};
    case SamplingMethod::sobol:
      if (d_ > kSobolMaxDims)
        return fmt::format(
            "d: sobol supports at most {} dimensions (Joe-Kuo direction numbers embedded up to "
            "dimension {}); got {}",
            kSobolMaxDims, kSobolMaxDims, d_);
      if (n_runs_ > (std::int64_t{1} << kSobolBits))
        return fmt::format("n_runs: sobol supports at most 2^{} runs (got {})", kSobolBits, n_runs_);
      return {};
    case SamplingMethod::saltelli: {
      if (d_ < 1) return fmt::format("d: saltelli needs d >= 1 (got {})", d_);
      if (std::string e = validate_groups(); !e.empty()) return e;
      const int factors = saltelli_factors();
      const std::int64_t block = saltelli_block(factors);
      if (n_runs_ % block != 0) {
        const std::string what =
            fmt::format("n_runs: saltelli needs a multiple of {} + 2 = {} (blocks A, B, AB_1..AB_{})",
                        groups_.empty() ? "d" : "G", block, factors);
        const std::int64_t below = n_runs_ / block;
        const std::int64_t above = below + 1;
        if (below == 0) return fmt::format("{}; got {}, nearest valid count is {} (N = 1)", what, n_runs_, block);
        return fmt::format("{}; got {}, nearest valid counts are {} (N = {}) and {} (N = {})", what, n_runs_,
                           below * block, below, above * block, above);
      }
      if (saltelli_uses_sobol() && n_runs_ / block > (std::int64_t{1} << kSobolBits))
        return fmt::format("n_runs: saltelli with a Sobol' base supports at most 2^{} blocks (got {})",
                           kSobolBits, n_runs_ / block);
      return {};
    }
  }
  return "method: unknown sampling method";
}

std::string SamplePlan::validate_groups() const {
  if (groups_.empty()) return {};
  std::int64_t sum = 0;
  for (std::size_t g = 0; g < groups_.size(); ++g) {
    if (groups_[g] < 1) return fmt::format("saltelli_groups: group {} has {} dimensions (needs >= 1)", g, groups_[g]);
    sum += groups_[g];
  }
  if (sum != d_) return fmt::format("saltelli_groups: the groups span {} dimensions, not d = {}", sum, d_);
  return {};
}

double SamplePlan::sobol_point_unshifted(std::uint32_t index, int dim) {
  if (dim < 0 || dim >= kSobolMaxDims)
    throw std::out_of_range(fmt::format("sobol_point_unshifted: dim {} outside [0, {})", dim, kSobolMaxDims));
  const std::uint32_t* V = sobol_table().data() + static_cast<std::size_t>(dim) * kSobolBits;
  std::uint32_t g = index ^ (index >> 1);
  std::uint32_t x = 0;
  for (int k = 0; g != 0; ++k, g >>= 1)
    if (g & 1u) x ^= V[k];
  return static_cast<double>(x) * 0x1p-32;
}

// Coordinates [first, first + count) of Sobol' point `index` as 32-bit
// integers. The point is the XOR of the direction numbers selected by the
// bits of the Gray code of the index (Antonov & Saleev 1979), which gives
// any index directly, with no state carried from previous runs.
void SamplePlan::calc_sobol(std::uint64_t index, int first, int count, std::uint32_t* x) const {
  std::fill(x, x + count, 0u);
  const auto ns = static_cast<std::size_t>(sobol_dims_);
  std::uint64_t g = index ^ (index >> 1);
  for (std::size_t k = 0; g != 0; ++k, g >>= 1) {
    if (!(g & 1u)) continue;
    const std::uint32_t* row = directions_.data() + k * ns + static_cast<std::size_t>(first);
    for (int j = 0; j < count; ++j) x[j] ^= row[j];
  }
}

// u_j = (pi_j(i) + v_ij) / n (sampling.hpp). Dimensions in blocks of kLanes, their permutations
// computed side by side (feistel_apply).
void SamplePlan::calc_latin_hypercube(std::int64_t run_index, double* u) const {
  const std::uint64_t jitter_state = counter_run_state(seed_, run_index, kTagLhsJitter);
  const auto n = static_cast<std::uint64_t>(n_runs_);
  const double dn = static_cast<double>(n_runs_);
  const auto nd = static_cast<std::size_t>(d_);
  std::uint64_t strata[kLanes];
  // Cycle walking: re-apply the bijection on [0, 2^bits) until the value lands in [0, n); this
  // restricts it to a bijection on [0, n). The lanes still outside, with their keys, are gathered
  // so that every pass runs on contiguous lanes: the chains that walk longest still have company.
  int walking[kLanes];
  std::uint64_t walk_x[kLanes], walk_keys[kFeistelRounds * kLanes];
  for (int j0 = 0; j0 < d_; j0 += kLanes) {
    const int m = std::min(kLanes, d_ - j0);
    std::fill(strata, strata + m, static_cast<std::uint64_t>(run_index));
    const std::uint64_t* keys = round_keys_.data() + j0;
    if (n > 1) feistel_apply(strata, m, feistel_bits_, keys, nd);
    // Compactions without branches (each lane is written, the count moves only for the walkers): at
    // n = 100,000 a quarter of the lanes walk, at random, which no branch predictor guesses.
    int k = 0;
    for (int l = 0; l < m; ++l) {
      walking[k] = l;
      walk_x[k] = strata[l];
      k += strata[l] >= n;
    }
    for (std::size_t r = 0; r < kFeistelRounds; ++r)
      for (int i = 0; i < k; ++i) walk_keys[r * kLanes + i] = keys[r * nd + static_cast<std::size_t>(walking[i])];
    while (k > 0) {
      feistel_apply(walk_x, k, feistel_bits_, walk_keys, kLanes);
      int still = 0;
      for (int i = 0; i < k; ++i) {
        strata[walking[i]] = walk_x[i];  // final once it lies in [0, n)
        walking[still] = walking[i];
        walk_x[still] = walk_x[i];
        for (std::size_t r = 0; r < kFeistelRounds; ++r) walk_keys[r * kLanes + still] = walk_keys[r * kLanes + i];
        still += walk_x[i] >= n;
      }
      k = still;
    }
    place_in_strata(strata, m, jitter_state, static_cast<std::uint64_t>(j0), dn, u + j0);
  }
}

void SamplePlan::calc_uniforms(std::int64_t run_index, double* u) const {
  if (!valid_) throw std::logic_error("SamplePlan::calc_uniforms on an invalid plan: " + validate());
  if (run_index < 0 || run_index >= n_runs_)
    throw std::out_of_range(
        fmt::format("SamplePlan::calc_uniforms: run_index {} outside [0, {})", run_index, n_runs_));

  switch (method_) {
    case SamplingMethod::monte_carlo: {
      const std::uint64_t state = counter_run_state(seed_, run_index, kTagMonteCarlo);
      for (int j = 0; j < d_; ++j) u[j] = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(j)));
      return;
    }
    case SamplingMethod::latin_hypercube:
      calc_latin_hypercube(run_index, u);
      return;
    case SamplingMethod::sobol: {
      // Run r is Sobol' point r: the origin is NOT dropped. The digital shift
      // already moves it away from 0, and dropping it would break the
      // balance of every block of 2^m points (Owen, "On dropping the first
      // Sobol' point", arXiv:2008.08051): with points 1..2^m the first
      // interval [0, 2^-m) of each coordinate is empty and another holds two.
      constexpr int kChunk = 256;
      std::array<std::uint32_t, kChunk> x{};
      for (int first = 0; first < d_; first += kChunk) {
        const int count = std::min(kChunk, d_ - first);
        calc_sobol(static_cast<std::uint64_t>(run_index), first, count, x.data());
        for (int j = 0; j < count; ++j) {
          const std::uint64_t z = (static_cast<std::uint64_t>(x[static_cast<std::size_t>(j)]) << 21) ^
                                  shifts_[static_cast<std::size_t>(first + j)];
          u[first + j] = static_cast<double>(z) * 0x1p-53;
        }
      }
      return;
    }
    case SamplingMethod::saltelli: {
      // Block b = base point b in 2d dimensions: A = its first d
      // coordinates, B = the last d. Position 0 -> A, 1 -> B, 2 + g -> AB_g
      // (A with the columns of factor g taken from B).
      const int block = saltelli_block(static_cast<int>(groups_.size()));
      const std::int64_t b = run_index / block;
      const int pos = static_cast<int>(run_index % block);
      const int from = (pos == 1) ? d_ : 0;  // columns [from, from + d) of the base point
      const int g = pos >= 2 ? pos - 2 : -1;
      const int swap_first = g >= 0 ? group_begin_[static_cast<std::size_t>(g)] : 0;
      const int swap_count = g >= 0 ? group_begin_[static_cast<std::size_t>(g) + 1] - swap_first : 0;
      if (saltelli_uses_sobol()) {
        auto coord = [&](std::uint32_t xi, int col) {
          const std::uint64_t z =
              (static_cast<std::uint64_t>(xi) << 21) ^ shifts_[static_cast<std::size_t>(col)];
          return static_cast<double>(z) * 0x1p-53;
        };
        constexpr int kChunk = 256;
        std::array<std::uint32_t, kChunk> x{};
        for (int first = 0; first < d_; first += kChunk) {
          const int count = std::min(kChunk, d_ - first);
          calc_sobol(static_cast<std::uint64_t>(b), from + first, count, x.data());
          for (int j = 0; j < count; ++j)
            u[first + j] = coord(x[static_cast<std::size_t>(j)], from + first + j);
        }
        for (int first = swap_first; first < swap_first + swap_count; first += kChunk) {
          const int count = std::min(kChunk, swap_first + swap_count - first);
          calc_sobol(static_cast<std::uint64_t>(b), d_ + first, count, x.data());
          for (int j = 0; j < count; ++j) u[first + j] = coord(x[static_cast<std::size_t>(j)], d_ + first + j);
        }
      } else {
        // Point b of the plain monte_carlo plan in 2d dimensions.
        const std::uint64_t state = counter_run_state(seed_, b, kTagMonteCarlo);
        for (int j = 0; j < d_; ++j)
          u[j] = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(from + j)));
        for (int j = swap_first; j < swap_first + swap_count; ++j)
          u[j] = to_open_unit(splitmix_at(state, static_cast<std::uint64_t>(d_ + j)));
      }
      return;
    }
  }
}

void SamplePlan::calc_values(std::int64_t run_index, std::span<const Distribution> dists, double* x) const {
  if (dists.size() != static_cast<std::size_t>(d_))
    throw std::invalid_argument(
        fmt::format("SamplePlan::calc_values: {} distributions for a plan of d = {}", dists.size(), d_));
  calc_uniforms(run_index, x);
  for (std::size_t j = 0; j < dists.size(); ++j) x[j] = dists[j].calc_quantile(x[j]);
}

}  // namespace truss::sampling
