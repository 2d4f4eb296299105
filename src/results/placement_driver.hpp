// The results file's HDF5 file driver: POSIX I/O as HDF5's default driver (sec2) does it, plus
// placement. While a Placement scope is open, the raw-data write of H5Dwrite_chunk's chunk bytes
// (given as Placement::kBytes) is not performed: the driver records where the bytes belong, HDF5
// allocates the space and indexes the chunk as usual, and the rank that encoded the chunk writes
// the bytes there itself (pwrite). Rank 0 keeps the file's metadata, the other ranks write the chunks they built:
// no rank handles every chunk's bytes. Metadata goes through the library's own caches and is
// written by rank 0 alone; the driver does not accumulate metadata writes (HDF5's metadata
// accumulator could otherwise hold a stale copy of bytes it never wrote).
//
// Built against HDF5 1.10's driver interface (H5FD_class_t of H5FDpublic.h), which later versions
// changed: the project is pinned to 1.10 (docs/architecture.md).
#pragma once
#include <hdf5.h>

#include <cstdint>

namespace truss::results {

// What a placed write recorded: the chunk's address in the file and its size (bytes).
struct ChunkAddress {
  std::uint64_t offset = 0, size = 0;
};

// One file's placement state, owned by its opener (CampaignFile), shared with the driver through
// the file access property list.
class PlacementState {
 public:
  bool placing() const { return placing_; }
  // While placing: the last raw-data write's address (the driver's side).
  void record(std::uint64_t offset, std::uint64_t size) {
    last_ = {offset, size};
    ++recorded_;
  }
  const ChunkAddress& last() const { return last_; }
  std::int64_t recorded() const { return recorded_; }

 private:
  friend class Placement;
  bool placing_ = false;
  ChunkAddress last_;
  std::int64_t recorded_ = 0;
};

// A file access property list that opens files through the placement driver with `state`.
hid_t make_placement_fapl(PlacementState& state);

// The scope of one H5Dwrite_chunk whose bytes another writer supplies: called with kBytes for the
// chunk's bytes, which the driver recognises (the write of exactly that buffer is recorded, not
// performed; every other write in the scope, such as the global heap that HDF5 writes as raw data
// when its cache makes room, is performed). Exactly one such write is recorded (address() throws
// std::runtime_error otherwise, e.g. when HDF5 wrote nothing).
class Placement {
 public:
  static const char kBytes[1];  // the buffer to give H5Dwrite_chunk: never read
  explicit Placement(PlacementState& s);
  ~Placement();
  Placement(const Placement&) = delete;
  Placement& operator=(const Placement&) = delete;
  ChunkAddress address() const;

 private:
  PlacementState& s_;
  std::int64_t recorded0_;
};

}  // namespace truss::results
