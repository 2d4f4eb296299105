// Large byte buffers kept for reuse. Rank 0 fills a results-file chunk of some 18 MB every 4,096
// runs and hands it out as encoding jobs; freeing the buffers once the jobs are sent and
// allocating the next chunk's anew cost page faults and zeroing on every chunk (about a tenth of
// rank 0's per-result work at 100,000 Table-1 runs, docs/benchmarks.md). The pool keeps them.
#pragma once
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace truss::campaign {

class BufferPool {
 public:
  // Buffers smaller than min_bytes are not worth keeping; at most limit_bytes are kept in all.
  void set_limit(std::size_t limit_bytes, std::size_t min_bytes = std::size_t{1} << 17) {
    limit_ = limit_bytes;
    min_ = min_bytes;
  }
  // The smallest kept buffer of at least `capacity` bytes, with whatever it holds (its size is
  // its old contents' size: a caller that overwrites it need not zero it), or a new empty one.
  std::string take(std::size_t capacity) {
    auto best = kept_.end();
    for (auto it = kept_.begin(); it != kept_.end(); ++it)
      if (it->capacity() >= capacity && (best == kept_.end() || it->capacity() < best->capacity())) best = it;
    std::string b;
    if (best == kept_.end()) {
      b.reserve(capacity);
      return b;
    }
    b = std::move(*best);
    bytes_ -= b.capacity();
    *best = std::move(kept_.back());
    kept_.pop_back();
    return b;
  }
  // A buffer no longer needed: kept, or freed if too small or over the limit.
  void give(std::string&& b) {
    if (b.capacity() < min_ || bytes_ + b.capacity() > limit_) return;
    bytes_ += b.capacity();
    kept_.push_back(std::move(b));
  }
  std::size_t bytes() const { return bytes_; }

 private:
  std::vector<std::string> kept_;
  std::size_t bytes_ = 0, limit_ = 0, min_ = 0;
};

}  // namespace truss::campaign
