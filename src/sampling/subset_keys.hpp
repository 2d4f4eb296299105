// subset_keys.hpp — the random-number keys of subset simulation (subset_simulation.hpp): every
// uniform is counter_uniform(seed, chain, dimension, subset_stream(level, step, stream)) of the
// counter-based generator (campaign/sampling.hpp), so it depends on (master seed, level, chain,
// step, dimension, stream) only, never on a rank or on the order results arrive in.
#pragma once
#include <cstdint>

#include "campaign/sampling.hpp"

namespace truss::sampling {

inline constexpr std::uint64_t kTagSubset = 0x5355425345542d53ULL;  // "SUBSET-S"
inline constexpr std::uint64_t kStreamLevel0 = 0;   // level 0: the point's uniforms
inline constexpr std::uint64_t kStreamPropose = 1;  // Markov step: the proposal's uniform
inline constexpr std::uint64_t kStreamAccept = 2;   // Markov step: the component's acceptance

// The `extra` key of the generator for one (level, step, stream): three chained SplitMix64
// steps, so that keys differing in any one part land in independent streams.
constexpr std::uint64_t subset_stream(int level, int step, std::uint64_t stream) noexcept {
  const std::uint64_t a = campaign::splitmix_at(kTagSubset, static_cast<std::uint64_t>(level));
  return campaign::splitmix_at(campaign::splitmix_at(a, static_cast<std::uint64_t>(step)), stream);
}

}  // namespace truss::sampling
