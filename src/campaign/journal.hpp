// The journal of a running campaign: an append-only file of framed records, each with its length
// and a CRC-32, behind a header holding the resolved campaign text. Rank 0 appends every finished
// run and flushes at least every few seconds. HDF5 1.10 files are not crash-safe while open for
// writing; a journal is: after kill -9 or a power cut, every complete record is still valid and a
// torn last record fails its CRC and is dropped. `truss-campaign --resume` reads it back.
//
// Layout (little-endian): "TRUSSJNL" u32 version, u32 text length, text, u32 CRC-32 of the text;
// then frames: u8 kind, u32 payload length, u32 CRC-32 of kind + payload, payload.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <stdexcept>
#include <string_view>
#include <vector>

namespace truss::campaign {

enum class FrameKind : std::uint8_t {
  run = 'R',       // a RunRecord
  session = 'S',   // an invocation started: f64 unix time, i32 rank count
  heartbeat = 'H'  // f64 wall time of the current invocation so far (s)
};

struct JournalFrame {
  FrameKind kind;
  std::string payload;
};

// What reading a journal back found. Frames are read up to the first one that fails its CRC or
// its framing (the damage); the file is cut there. The rest of the file is then scanned (at every
// byte) for frames that would still pass, to tell a torn last record (a crash while appending:
// nothing valid after it) from a damaged middle (valid records after it, dropped and recomputed).
struct JournalScan {
  std::int64_t frames_kept = 0, records_kept = 0;  // delivered to the caller (records: run frames)
  std::size_t damage_offset = 0;                   // byte offset of the first bad frame (if any)
  std::size_t dropped_bytes = 0;                   // from damage_offset to the end of the file
  std::int64_t records_dropped = 0;                // valid run frames found after the damage
  bool damaged_middle() const { return records_dropped > 0; }
  std::string describe(const std::string& path) const;  // "" when nothing was dropped
};

// A journal that must not be used: it belongs to another campaign, or a live process holds it.
struct JournalRefused : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// While open, a journal holds an exclusive flock(): a second truss-campaign on the same output
// (for example --resume while ranks of a killed mpirun still run) is refused instead of
// interleaving its writes. The lock dies with its process.
class Journal {
 public:
  // Creates a new journal (fails if `path` exists) holding `campaign_text`.
  static Journal create(const std::string& path, const std::string& campaign_text);
  // Opens an existing journal for appending after reading its frames into `frames`. A torn or
  // corrupt tail is cut off (the file is truncated at the last good frame). Throws
  // std::runtime_error if the header is unreadable, and JournalRefused if it holds a different
  // campaign text or another process has it open.
  static Journal resume(const std::string& path, const std::string& campaign_text, std::vector<JournalFrame>& frames,
                        std::size_t& dropped_bytes);
  // Same, handing each good frame to on_frame as it is read (the payload view is valid during
  // the call only; `offset` is the frame's byte offset in the file): memory stays bounded
  // whatever the journal's size. An exception from on_frame propagates and leaves the file as
  // it was (nothing is cut).
  using FrameFn = std::function<void(FrameKind, std::string_view payload, std::size_t offset)>;
  static Journal resume(const std::string& path, const std::string& campaign_text, const FrameFn& on_frame,
                        JournalScan& scan);
  Journal(Journal&&) noexcept;
  Journal& operator=(Journal&&) = delete;
  Journal(const Journal&) = delete;
  ~Journal();

  // Removes an unfinished journal (--force); JournalRefused if a live process holds it.
  static void remove_unused(const std::string& path);

  // Buffered; a buffer of kWriteThrough bytes goes to the background writer (below), which writes
  // it out (not synced), so memory stays bounded however long the flush interval.
  void append(FrameKind kind, std::string_view payload);
  static std::uint32_t frame_crc(FrameKind kind, std::string_view payload);
  // Frames made where the record is made (a worker, which takes the CRC off rank 0's per-result
  // work): kFrameHeader bytes, then the payload; seal_frame fills the header (kind, length, CRC).
  static constexpr std::size_t kFrameHeader = 9;
  static void seal_frame(std::string& frame, FrameKind kind);
  // A sealed frame, copied. Throws std::runtime_error, appending nothing, if its length field does
  // not match its size (its CRC is checked when the journal is read back).
  void append_frame(std::string_view frame);
  // Sealed frames that live in `owner` (a received message): the writer writes them from there
  // and then releases its reference, so rank 0 copies nothing. They follow every frame appended
  // before. Checked as append_frame's, all before any is queued.
  void append_frames(std::shared_ptr<const void> owner, const std::vector<std::string_view>& frames);
  static constexpr std::size_t kWriteThrough = std::size_t{1} << 20;
  // The kernel's copy of each record into the page cache and the fdatasync waits are rank 0's
  // per-result work on the campaign's serial path (docs/benchmarks.md, fourth look): a background
  // thread does them. Buffers are written in the order they were handed over; at most
  // kMaxQueuedBytes wait (append then blocks), and a write or sync error is rethrown by the next
  // append or flush of the owner.
  static constexpr std::size_t kMaxQueuedBytes = std::size_t{8} << 20;
  void flush();             // hands the buffer over and waits until it is written and fdatasync'ed: on disk from now on
  // The same without waiting (periodic flushes): on disk shortly, or an error from the next call.
  // `then` (optional, must not throw) runs on the writer thread once the buffer is synced.
  void flush_async(std::function<void()> then = {});
  void close_and_remove();  // after the results file is in place
  const std::string& path() const { return path_; }

 private:
  struct Writer;
  Journal(std::string path, int fd);
  std::uint64_t hand_over(bool sync, std::function<void()> then = {});  // the writer's ticket for this buffer
  Writer& writer();  // started at the first use
  std::string path_;
  int fd_ = -1;
  std::string buffer_;
  std::unique_ptr<Writer> writer_;
};

std::uint32_t crc32_of(std::string_view bytes);

}  // namespace truss::campaign
