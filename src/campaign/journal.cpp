#include "campaign/journal.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/uio.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

namespace truss::campaign {

namespace {

constexpr char kMagic[8] = {'T', 'R', 'U', 'S', 'S', 'J', 'N', 'L'};
constexpr std::uint32_t kVersion = 1;

[[noreturn]] void fail_errno(const std::string& what, const std::string& path) {
  throw std::runtime_error(fmt::format("{} {}: {}", what, path, std::strerror(errno)));
}

template <class T>
void put(std::string& out, T v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
bool get(std::string_view b, std::size_t& at, T& v) {
  if (b.size() - at < sizeof(T)) return false;
  std::memcpy(&v, b.data() + at, sizeof(T));
  at += sizeof(T);
  return true;
}

// Writes every piece, in order, with as few writev calls as the kernel allows (a short write
// resumes inside the piece it stopped in).
void writev_all(int fd, std::vector<iovec>& v, const std::string& path) {
  std::size_t first = 0;
  while (first < v.size()) {
    const int count = static_cast<int>(std::min<std::size_t>(v.size() - first, IOV_MAX));
    ssize_t n = ::writev(fd, v.data() + first, count);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_errno("cannot write journal", path);
    }
    while (first < v.size() && static_cast<std::size_t>(n) >= v[first].iov_len) n -= static_cast<ssize_t>(v[first++].iov_len);
    if (first < v.size()) {
      v[first].iov_base = static_cast<char*>(v[first].iov_base) + n;
      v[first].iov_len -= static_cast<std::size_t>(n);
    }
  }
}

// A sealed frame's length field against its size.
void check_frame(std::string_view frame) {
  std::uint32_t size = 0;
  if (frame.size() >= Journal::kFrameHeader) std::memcpy(&size, frame.data() + 1, 4);
  if (frame.size() < Journal::kFrameHeader || size != frame.size() - Journal::kFrameHeader)
    throw std::runtime_error(fmt::format("a result of {} bytes is not a sealed journal frame", frame.size()));
}

void lock_or_refuse(int fd, const std::string& path) {
  if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return;
  const int err = errno;
  ::close(fd);
  if (err == EWOULDBLOCK)
    throw JournalRefused(fmt::format("{} is in use by another running truss-campaign (perhaps ranks of a killed "
                                     "mpirun are still running: stop them first)", path));
  errno = err;
  fail_errno("cannot lock journal", path);
}

}  // namespace

// The background writer: write()s the buffers handed over, in order, and fdatasyncs after those
// marked sync. After an error it writes nothing more (a gap would leave valid frames after a
// missing one) and every later call of the owner rethrows the error.
struct Journal::Writer {
  Writer(int fd, std::string path) : fd_(fd), path_(std::move(path)), thread_([this] { loop(); }) {}
  ~Writer() {
    {
      std::lock_guard<std::mutex> l(m_);
      stop_ = true;
    }
    work_.notify_all();
    thread_.join();
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // The owner's side, not shared with the thread: frames are staged, then handed over together
  // (one lock and one wake-up a megabyte, not one a message). stage() moves the journal's buffer in
  // and gives `bytes` an empty written one back (its memory kept); stage_owned() takes frames that
  // live in `owner`, which is kept until they are written: no copy.
  void stage(std::string& bytes) {
    Item& it = staged_.emplace_back();
    it.size = bytes.size();
    it.bytes = std::move(bytes);
    staged_bytes_ += it.size;
    bytes.clear();
    std::lock_guard<std::mutex> l(m_);
    if (!spare_.empty()) {
      bytes = std::move(spare_.back());
      spare_.pop_back();
    }
  }
  void stage_owned(std::shared_ptr<const void> owner, std::vector<iovec> pieces, std::size_t bytes) {
    Item& it = staged_.emplace_back();
    it.owner = std::move(owner);
    it.pieces = std::move(pieces);
    it.size = bytes;
    staged_bytes_ += bytes;
  }
  std::size_t staged_bytes() const { return staged_bytes_; }
  // Queues what is staged (an empty item if nothing, so that a sync still happens), the last item
  // syncing if asked; returns the ticket that wait() takes. Blocks while kMaxQueuedBytes wait.
  std::uint64_t submit(bool sync, std::function<void()> then = {}) {
    if (staged_.empty()) staged_.emplace_back();
    staged_.back().sync = sync;
    staged_.back().then = std::move(then);
    std::unique_lock<std::mutex> l(m_);
    space_.wait(l, [&] { return queued_ < kMaxQueuedBytes || error_; });
    if (error_) std::rethrow_exception(error_);
    for (Item& it : staged_) {
      queued_ += it.size;
      queue_.push_back(std::move(it));
    }
    submitted_ += staged_.size();
    staged_.clear();
    staged_bytes_ = 0;
    work_.notify_one();
    return submitted_;
  }
  void wait(std::uint64_t ticket) {
    std::unique_lock<std::mutex> l(m_);
    done_.wait(l, [&] { return completed_ >= ticket || error_; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  struct Item {
    std::string bytes;                   // a buffer of the journal's own frames, or
    std::shared_ptr<const void> owner;  // ... memory holding frames elsewhere (pieces point into it)
    std::vector<iovec> pieces;
    std::size_t size = 0;
    bool sync = false;
    std::function<void()> then;
  };
  // The items waiting, up to the first that syncs (or kMaxBatch of them): written together.
  static constexpr std::size_t kMaxBatch = 64;
  void loop() {
    std::unique_lock<std::mutex> l(m_);
    std::vector<Item> batch;
    std::vector<iovec> v;
    for (;;) {
      work_.wait(l, [&] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopping, everything written
      batch.clear();
      while (!queue_.empty() && batch.size() < kMaxBatch) {
        batch.push_back(std::move(queue_.front()));
        queue_.pop_front();
        if (batch.back().sync) break;
      }
      l.unlock();
      std::exception_ptr err;
      try {
        v.clear();
        for (Item& it : batch) {
          if (it.owner) v.insert(v.end(), it.pieces.begin(), it.pieces.end());
          else if (!it.bytes.empty()) v.push_back({it.bytes.data(), it.bytes.size()});
        }
        writev_all(fd_, v, path_);
        if (batch.back().sync && ::fdatasync(fd_) != 0) fail_errno("cannot sync journal", path_);
        if (batch.back().then) batch.back().then();
      } catch (...) {
        err = std::current_exception();
      }
      l.lock();
      for (Item& it : batch) queued_ -= it.size;
      if (err) {
        error_ = err;
        queue_.clear();
        queued_ = 0;
      } else {
        completed_ += batch.size();
        for (Item& it : batch) {
          if (it.owner || spare_.size() >= 2) continue;
          it.bytes.clear();
          spare_.push_back(std::move(it.bytes));
        }
      }
      batch.clear();  // owners released
      space_.notify_all();
      done_.notify_all();
    }
  }

  int fd_;
  std::string path_;
  std::mutex m_;
  std::condition_variable work_, space_, done_;
  std::deque<Item> queue_;
  std::vector<Item> staged_;  // the owner's, unlocked
  std::size_t staged_bytes_ = 0;
  std::vector<std::string> spare_;
  std::size_t queued_ = 0;
  std::uint64_t submitted_ = 0, completed_ = 0;
  std::exception_ptr error_;
  bool stop_ = false;
  std::thread thread_;  // last: started once the members above exist
};

Journal::Journal(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}

void Journal::remove_unused(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail_errno("cannot open journal", path);
  lock_or_refuse(fd, path);
  if (::unlink(path.c_str()) != 0) fail_errno("cannot remove journal", path);
  ::close(fd);
}

std::uint32_t crc32_of(std::string_view bytes) {
  return static_cast<std::uint32_t>(
      ::crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size())));
}

Journal Journal::create(const std::string& path, const std::string& campaign_text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) fail_errno("cannot create journal", path);
  lock_or_refuse(fd, path);
  Journal j(path, fd);
  std::string h(kMagic, sizeof kMagic);
  put(h, kVersion);
  put(h, static_cast<std::uint32_t>(campaign_text.size()));
  h += campaign_text;
  put(h, crc32_of(campaign_text));
  j.buffer_ = std::move(h);
  j.flush();
  return j;
}

namespace {

// Reads a file forward in blocks, keeping the unconsumed bytes.
class BlockReader {
 public:
  BlockReader(int fd, const std::string& path) : fd_(fd), path_(path) {}
  // True once at least n bytes are buffered past the read position (false at end of file).
  bool need(std::size_t n) {
    while (buf_.size() - at_ < n) {
      if (at_ > (std::size_t{1} << 20)) {  // drop what has been consumed
        buf_.erase(0, at_);
        at_ = 0;
      }
      char block[1 << 16];
      const ssize_t got = ::read(fd_, block, sizeof block);
      if (got < 0) {
        if (errno == EINTR) continue;
        fail_errno("cannot read journal", path_);
      }
      if (got == 0) return false;
      buf_.append(block, static_cast<std::size_t>(got));
    }
    return true;
  }
  std::string_view view(std::size_t n) const { return {buf_.data() + at_, n}; }
  void skip(std::size_t n) {
    at_ += n;
    offset_ += n;
  }
  std::size_t offset() const { return offset_; }  // of the read position, from the start of the file

 private:
  int fd_;
  const std::string& path_;
  std::string buf_;
  std::size_t at_ = 0, offset_ = 0;
};

// The header: magic, version, campaign text, CRC. Throws unless it holds `campaign_text`.
void read_header(BlockReader& r, const std::string& path, const std::string& campaign_text) {
  const std::size_t head = sizeof kMagic + 2 * sizeof(std::uint32_t);
  if (!r.need(head) || std::memcmp(r.view(sizeof kMagic).data(), kMagic, sizeof kMagic) != 0)
    throw std::runtime_error(fmt::format("{} is not a truss-campaign journal", path));
  std::uint32_t version = 0, len = 0, crc = 0;
  std::size_t at = sizeof kMagic;
  get(r.view(head), at, version);
  get(r.view(head), at, len);
  if (version != kVersion || !r.need(head + len + sizeof crc))
    throw std::runtime_error(fmt::format("{}: unreadable journal header", path));
  const std::string_view all = r.view(head + len + sizeof crc);
  const std::string_view text = all.substr(head, len);
  at = head + len;
  get(all, at, crc);
  if (crc != crc32_of(text)) throw std::runtime_error(fmt::format("{}: damaged journal header", path));
  if (text != campaign_text)
    throw JournalRefused(fmt::format("{} belongs to a different campaign (resolved campaign text differs); "
                                      "finish it with the same campaign file and --set options, or start over with --force", path));
  r.skip(head + len + sizeof crc);
}

constexpr std::size_t kFrameHead = 1 + 2 * sizeof(std::uint32_t);
constexpr std::uint32_t kMaxPayload = std::uint32_t{1} << 26;  // 64 MiB: a record is a few kB

bool known_kind(std::uint8_t k) {
  return k == static_cast<std::uint8_t>(FrameKind::run) || k == static_cast<std::uint8_t>(FrameKind::session) ||
         k == static_cast<std::uint8_t>(FrameKind::heartbeat);
}

// The frame at the read position if it is complete, of a known kind and passes its CRC.
bool frame_at(BlockReader& r, std::size_t bytes_left, std::uint8_t& kind, std::string_view& payload) {
  if (!r.need(kFrameHead)) return false;
  std::uint32_t n = 0, c = 0;
  std::size_t at = 0;
  const std::string_view h = r.view(kFrameHead);
  get(h, at, kind);
  get(h, at, n);
  get(h, at, c);
  if (!known_kind(kind) || n > kMaxPayload || n > bytes_left - kFrameHead || !r.need(kFrameHead + n)) return false;
  payload = r.view(kFrameHead + n).substr(kFrameHead);
  const auto k = static_cast<Bytef>(kind);
  uLong crc = ::crc32(0L, &k, 1);
  crc = ::crc32(crc, reinterpret_cast<const Bytef*>(payload.data()), static_cast<uInt>(payload.size()));
  return c == static_cast<std::uint32_t>(crc);
}

}  // namespace

std::string JournalScan::describe(const std::string& path) const {
  if (dropped_bytes == 0) return "";
  if (!damaged_middle())
    return fmt::format("{}: torn last record dropped ({} bytes at byte {}); {} records kept", path, dropped_bytes,
                       damage_offset, records_kept);
  return fmt::format("{}: damaged in the middle at byte {}: {} records before the damage kept, {} valid records after "
                     "it dropped ({} bytes) and computed again", path, damage_offset, records_kept, records_dropped,
                     dropped_bytes);
}

Journal Journal::resume(const std::string& path, const std::string& campaign_text, const FrameFn& on_frame,
                        JournalScan& scan) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) fail_errno("cannot open journal", path);
  lock_or_refuse(fd, path);
  Journal j(path, fd);
  const off_t size = ::lseek(fd, 0, SEEK_END);
  if (size < 0 || ::lseek(fd, 0, SEEK_SET) < 0) fail_errno("cannot seek journal", path);
  const auto file_size = static_cast<std::size_t>(size);
  BlockReader r(fd, path);
  read_header(r, path, campaign_text);
  scan = JournalScan{};
  std::uint8_t kind = 0;
  std::string_view payload;
  while (r.offset() < file_size && frame_at(r, file_size - r.offset(), kind, payload)) {
    on_frame(static_cast<FrameKind>(kind), payload, r.offset());
    ++scan.frames_kept;
    scan.records_kept += kind == static_cast<std::uint8_t>(FrameKind::run);
    r.skip(kFrameHead + payload.size());
  }
  const std::size_t good = r.offset();
  scan.damage_offset = good;
  scan.dropped_bytes = file_size - good;
  // After the damage: count the frames that still pass, at any byte (their framing is lost).
  if (good < file_size) r.skip(1);
  while (r.offset() < file_size) {
    if (frame_at(r, file_size - r.offset(), kind, payload)) {
      scan.records_dropped += kind == static_cast<std::uint8_t>(FrameKind::run);
      r.skip(kFrameHead + payload.size());
    } else {
      r.skip(1);
    }
  }
  if (scan.dropped_bytes > 0 && ::ftruncate(fd, static_cast<off_t>(good)) != 0) fail_errno("cannot truncate journal", path);
  if (::lseek(fd, static_cast<off_t>(good), SEEK_SET) < 0) fail_errno("cannot seek journal", path);
  return j;
}

Journal Journal::resume(const std::string& path, const std::string& campaign_text, std::vector<JournalFrame>& frames,
                        std::size_t& dropped_bytes) {
  frames.clear();
  JournalScan scan;
  Journal j = resume(
      path, campaign_text,
      [&](FrameKind k, std::string_view p, std::size_t) { frames.push_back({k, std::string(p)}); }, scan);
  dropped_bytes = scan.dropped_bytes;
  return j;
}

Journal::Journal(Journal&& o) noexcept
    : path_(std::move(o.path_)), fd_(o.fd_), buffer_(std::move(o.buffer_)), writer_(std::move(o.writer_)) {
  o.fd_ = -1;
}

Journal::~Journal() {
  if (fd_ >= 0) {
    try {
      flush();
    } catch (...) {
    }
    writer_.reset();  // joins the thread before the descriptor goes
    ::close(fd_);
  }
}

std::uint32_t Journal::frame_crc(FrameKind kind, std::string_view payload) {
  // CRC-32 of kind + payload, without building that string.
  const auto k = static_cast<Bytef>(kind);
  uLong crc = ::crc32(0L, &k, 1);
  crc = ::crc32(crc, reinterpret_cast<const Bytef*>(payload.data()), static_cast<uInt>(payload.size()));
  return static_cast<std::uint32_t>(crc);
}

void Journal::append(FrameKind kind, std::string_view payload) {
  put(buffer_, static_cast<std::uint8_t>(kind));
  put(buffer_, static_cast<std::uint32_t>(payload.size()));
  put(buffer_, frame_crc(kind, payload));
  buffer_.append(payload);
  // Bounded memory: full buffers go to the writer (no sync; flush() syncs).
  if (buffer_.size() >= kWriteThrough) hand_over(false);
}

void Journal::seal_frame(std::string& frame, FrameKind kind) {
  if (frame.size() < kFrameHeader) throw std::logic_error("a journal frame shorter than its header");
  const std::string_view payload = std::string_view(frame).substr(kFrameHeader);
  const std::uint32_t size = static_cast<std::uint32_t>(payload.size()), crc = frame_crc(kind, payload);
  frame[0] = static_cast<char>(kind);
  std::memcpy(frame.data() + 1, &size, 4);
  std::memcpy(frame.data() + 5, &crc, 4);
}

void Journal::append_frame(std::string_view frame) {
  check_frame(frame);
  buffer_.append(frame);
  if (buffer_.size() >= kWriteThrough) hand_over(false);
}

void Journal::append_frames(std::shared_ptr<const void> owner, const std::vector<std::string_view>& frames) {
  if (frames.empty()) return;
  std::vector<iovec> pieces;
  pieces.reserve(frames.size());
  std::size_t bytes = 0;
  for (std::string_view f : frames) {
    check_frame(f);
    pieces.push_back({const_cast<char*>(f.data()), f.size()});
    bytes += f.size();
  }
  Writer& w = writer();
  if (!buffer_.empty()) w.stage(buffer_);  // the frames before these go first
  w.stage_owned(std::move(owner), std::move(pieces), bytes);
  if (w.staged_bytes() >= kWriteThrough) w.submit(false);
}

Journal::Writer& Journal::writer() {
  if (!writer_) writer_ = std::make_unique<Writer>(fd_, path_);
  return *writer_;
}

std::uint64_t Journal::hand_over(bool sync, std::function<void()> then) {
  Writer& w = writer();
  if (!buffer_.empty()) w.stage(buffer_);
  return w.submit(sync, std::move(then));
}

void Journal::flush() {
  const std::uint64_t ticket = hand_over(true);
  writer_->wait(ticket);
}

void Journal::flush_async(std::function<void()> then) { hand_over(true, std::move(then)); }

void Journal::close_and_remove() {
  flush();
  writer_.reset();
  ::close(fd_);
  fd_ = -1;
  if (::unlink(path_.c_str()) != 0) fail_errno("cannot remove journal", path_);
}

}  // namespace truss::campaign
