// The byte images of what a chunk's builder and rank 0 exchange (chunk_builder.hpp): round parts,
// chunk reports (builder -> rank 0) and placements with the statistics windows (rank 0 -> builder;
// also the first windows, builder -> rank 0). Little-endian (util/bytes.hpp); the readers throw
// std::runtime_error for bytes that are not one image of the kind.
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "results/chunk_builder.hpp"
#include "results/placement_driver.hpp"

namespace truss::results {

// i64 round, i64 first_run, i64 n, n x i8 status, then per observed output n x f64.
std::string to_bytes(const RoundPart& p);
RoundPart read_round_part(std::string_view bytes, std::size_t n_outputs);

// i64 index, i64 rows, u32 datasets, per dataset u64 size and u32 mask, u32 summaries, each summary
// (windows, moments, the window counts and the kept values), u32 messages, each i64 row + text.
std::string to_bytes(const ChunkReport& r);
// Into `r` (its summaries' room used again).
void read_chunk_report(std::string_view bytes, ChunkReport& r);

// Where a chunk's datasets go and the windows to summarise the next chunks against (index -1 and
// no addresses: windows alone).
struct ChunkPlacement {
  std::int64_t index = 0;
  std::vector<ChunkAddress> addresses;       // per dataset
  std::vector<statistics::Windows> windows;  // per statistics column
};
std::string to_bytes(const ChunkPlacement& p);
ChunkPlacement read_chunk_placement(std::string_view bytes);

}  // namespace truss::results
