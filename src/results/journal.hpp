// The journals of a running campaign: append-only files of frames. Rank 0's journal (RESULTS.h5.
// journal) holds the resolved campaign text, every session, round plan and heartbeat, and the
// records of the chunks rank 0 builds; each other rank that builds chunks keeps a part journal of
// their records (RESULTS.h5.journal.SESSION.RANK), written where the records arrive, so that no rank
// writes every record. Each is written out a megabyte at a time and synced every flush interval.
// HDF5 1.10 files are not crash-safe while open for writing; a journal is: after kill -9 or a power
// cut every complete frame is still valid and a torn last frame fails its CRC and is dropped.
// `truss-campaign --resume` reads them back (parallel/engine.hpp, Collector::restore).
//
// Layout (little-endian): rank 0's: "TRUSSJNL" u32 version, u32 text length, text, u32 CRC-32 of
// the text; a part: "TRUSSJNP" u32 version, u32 CRC-32 of the campaign text, i64 session, i32 rank,
// u32 CRC-32 of the header before it. Then frames: u8 kind, u32 payload length, u32 CRC-32 of kind
// + payload, payload. A record's frame is sealed where the run ran and journaled as it came.
#pragma once
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace truss::results {

enum class FrameKind : std::uint8_t {
  run = 'R',       // a run's record (campaign/record.hpp)
  plan = 'P',      // a round's plan's digest (methods/method.hpp, PlanDigest), before any record of the round
  session = 'S',   // an invocation started: f64 unix time, i32 rank count
  heartbeat = 'H'  // f64 wall time of the current invocation so far (s)
};

inline constexpr std::size_t kFrameHeader = 9;  // u8 kind, u32 payload length, u32 CRC-32

// Builds a frame at the end of `out`: begin_frame appends the header's room and returns where the
// frame starts, the caller appends the payload, seal_frame fills the header (length and CRC).
std::size_t begin_frame(std::string& out);
void seal_frame(std::string& out, std::size_t start, FrameKind kind);

// One frame of a batch message: its kind, its payload and the whole frame's bytes. Throws
// std::runtime_error if `bytes` does not begin with a whole frame.
struct Frame {
  FrameKind kind;
  std::string_view payload, bytes;
};
Frame read_frame(std::string_view bytes);

// What reading a journal back found. Frames are read up to the first one that fails its CRC or
// its framing (the damage); the file is cut there. The rest of the file is then scanned (at every
// byte) for frames that would still pass, to tell a torn last record (a crash while appending:
// nothing valid after it) from a damaged middle (valid records after it, dropped and recomputed).
struct JournalScan {
  std::int64_t frames_kept = 0, records_kept = 0;  // read back (records: run frames)
  std::size_t damage_offset = 0;                   // byte offset of the first bad frame (if any)
  std::size_t dropped_bytes = 0;                   // from damage_offset to the end of the file
  std::int64_t records_dropped = 0;                // valid run frames found after the damage
  bool damaged_middle() const { return records_dropped > 0; }
  std::string describe(const std::string& path) const;  // "" when nothing was dropped
};

// A journal that must not be used: it belongs to another campaign.
struct JournalRefused : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The size of a part journal's header: a shorter part journal was cut before its header was
// written out (its rank killed at its first record), and holds no record.
inline constexpr std::size_t kPartHeaderBytes = 8 + 4 + 4 + 8 + 4 + 4;

// The part journal of `rank` in session `session` of the campaign writing `output`.
std::string part_journal_path(const std::string& output, std::int64_t session, int rank);
// Removes every part journal of `output` (OUTPUT.journal.S.R); returns their paths. Call while
// holding the output's lock.
std::vector<std::string> remove_part_journals(const std::string& output);

// A journal takes no lock of its own: its campaign holds the output's lock (results/lock_file.hpp,
// CampaignFile::lock_name) from before the journal is opened until after it is removed.
class Journal {
 public:
  // Creates a new journal (fails if `path` exists) holding `campaign_text`, synced.
  static Journal create(const std::string& path, const std::string& campaign_text);
  // Creates a part journal (fails if `path` exists) of `rank` in `session`, synced.
  static Journal create_part(const std::string& path, std::uint32_t campaign_crc, std::int64_t session, int rank);
  // Opens an existing journal to read its frames (next_frame) and then append. Throws
  // std::runtime_error if the header is unreadable, and JournalRefused if it holds a different
  // campaign text.
  static Journal open_existing(const std::string& path, const std::string& campaign_text);
  // The same for a part journal: JournalRefused unless it is the part of `rank` in `session` of
  // the campaign whose text has CRC-32 `campaign_crc`.
  static Journal open_part(const std::string& path, std::uint32_t campaign_crc, std::int64_t session, int rank);
  // The next good frame of an existing journal (its payload valid until the next call; `offset`
  // its byte offset in the file), or false at the end or at the first bad frame.
  bool next_frame(FrameKind& kind, std::string_view& payload, std::size_t& offset);
  // After next_frame has returned false (or once the frames before `cut` are read): scans what
  // follows the last good frame, cuts the file at the first bad frame or at `cut` (a byte offset
  // of a frame, whichever comes first) and leaves the journal ready for appending. Until then the
  // file is as it was.
  JournalScan finish_reading(std::size_t cut = SIZE_MAX);

  Journal(Journal&&) noexcept;
  Journal& operator=(Journal&&) = delete;
  Journal(const Journal&) = delete;
  ~Journal();  // writes the buffer out (not synced)

  // Buffered; a full buffer (kWriteThrough bytes) is written out (not synced). After a write or
  // sync error, every call throws that error and nothing more is written.
  void append(FrameKind kind, std::string_view payload);
  void append_frame(std::string_view sealed_frame);
  static constexpr std::size_t kWriteThrough = std::size_t{1} << 20;
  void write_out();         // writes the buffer out (not synced): it survives the process
  void flush();             // writes the buffer out and fdatasyncs: on disk from now on
  void close_and_remove();  // after the results file is in place (nothing written or synced first)
  const std::string& path() const { return path_; }

 private:
  class Reader;
  Journal(std::string path, int fd);
  void write_buffer();
  std::string path_;
  int fd_ = -1;
  std::string buffer_;
  std::string error_;               // of the first failed write or sync
  std::unique_ptr<Reader> reader_;  // while an existing journal is read
};

}  // namespace truss::results
