#include "results/journal.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>

#include "util/bytes.hpp"
#include "util/isal.hpp"

namespace truss::results {

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'T', 'R', 'U', 'S', 'S', 'J', 'N', 'L'};
constexpr char kPartMagic[8] = {'T', 'R', 'U', 'S', 'S', 'J', 'N', 'P'};
// 4: a round plan's digest, not its state ('P' frames); 3: records also in part journals (the ranks
// that build chunks); 2: round plans ('P' frames) and the record with its round (campaign/record.hpp).
constexpr std::uint32_t kVersion = 4;
constexpr std::size_t kPartHeader = kPartHeaderBytes;

std::string part_header(std::uint32_t campaign_crc, std::int64_t session, int rank) {
  std::string h(kPartMagic, sizeof kPartMagic);
  util::put(h, kVersion);
  util::put(h, campaign_crc);
  util::put(h, session);
  util::put(h, static_cast<std::int32_t>(rank));
  util::put(h, util::calc_crc32(h));
  return h;
}
constexpr std::uint32_t kMaxPayload = std::uint32_t{1} << 26;  // 64 MiB: a record is a few kB

[[noreturn]] void fail_errno(const std::string& what, const std::string& path) {
  throw std::runtime_error(fmt::format("{} {}: {}", what, path, std::strerror(errno)));
}

void write_all(int fd, std::string_view bytes, const std::string& path) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_errno("cannot write journal", path);
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
}

bool known_kind(std::uint8_t k) {
  return k == static_cast<std::uint8_t>(FrameKind::run) || k == static_cast<std::uint8_t>(FrameKind::plan) ||
         k == static_cast<std::uint8_t>(FrameKind::session) || k == static_cast<std::uint8_t>(FrameKind::heartbeat);
}

std::uint32_t frame_crc(std::uint8_t kind, std::string_view payload) {
  return util::calc_crc32(payload, util::calc_crc32(std::string_view(reinterpret_cast<const char*>(&kind), 1)));
}

}  // namespace

std::size_t begin_frame(std::string& out) {
  const std::size_t start = out.size();
  out.append(kFrameHeader, '\0');
  return start;
}

void seal_frame(std::string& out, std::size_t start, FrameKind kind) {
  const std::string_view payload = std::string_view(out).substr(start + kFrameHeader);
  const auto k = static_cast<std::uint8_t>(kind);
  out[start] = static_cast<char>(k);
  util::put_at(out.data() + start + 1, static_cast<std::uint32_t>(payload.size()));
  util::put_at(out.data() + start + 5, frame_crc(k, payload));
}

Frame read_frame(std::string_view bytes) {
  if (bytes.size() < kFrameHeader)
    throw std::runtime_error(fmt::format("a frame of {} bytes, shorter than its header", bytes.size()));
  const auto n = util::get_at<std::uint32_t>(bytes.data() + 1);
  if (n > bytes.size() - kFrameHeader)
    throw std::runtime_error(fmt::format("a frame of {} bytes cut to {}", std::size_t{n} + kFrameHeader, bytes.size()));
  return {static_cast<FrameKind>(bytes[0]), bytes.substr(kFrameHeader, n), bytes.substr(0, kFrameHeader + n)};
}

// Reads a journal forward in blocks, keeping the unconsumed bytes.
class Journal::Reader {
 public:
  Reader(int fd, std::string path, std::size_t file_size) : fd_(fd), path_(std::move(path)), size_(file_size) {}
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
  std::size_t left() const { return size_ - offset_; }
  // The frame at the read position if it is complete, of a known kind and passes its CRC.
  bool frame_at(std::uint8_t& kind, std::string_view& payload) {
    if (left() < kFrameHeader || !need(kFrameHeader)) return false;
    const std::string_view h = view(kFrameHeader);
    kind = static_cast<std::uint8_t>(h[0]);
    const auto n = util::get_at<std::uint32_t>(h.data() + 1), crc = util::get_at<std::uint32_t>(h.data() + 5);
    if (!known_kind(kind) || n > kMaxPayload || n > left() - kFrameHeader || !need(kFrameHeader + n)) return false;
    payload = view(kFrameHeader + n).substr(kFrameHeader);
    return crc == frame_crc(kind, payload);
  }
  // The header: magic, version, campaign text, CRC. Throws unless it holds `campaign_text`.
  void read_header(const std::string& campaign_text) {
    const std::size_t head = sizeof kMagic + 2 * sizeof(std::uint32_t);
    if (!need(head) || std::memcmp(view(sizeof kMagic).data(), kMagic, sizeof kMagic) != 0)
      throw std::runtime_error(fmt::format("{} is not a truss-campaign journal", path_));
    const auto version = util::get_at<std::uint32_t>(view(head).data() + sizeof kMagic);
    const auto len = util::get_at<std::uint32_t>(view(head).data() + sizeof kMagic + 4);
    if (version != kVersion)
      throw std::runtime_error(fmt::format("{}: unreadable journal header (version {}, this program writes {})", path_,
                                           version, kVersion));
    if (!need(head + len + 4))
      throw std::runtime_error(fmt::format("{}: truncated journal header ({} bytes of the file, the header says {})",
                                           path_, size_, head + len + 4));
    const std::string_view text = view(head + len).substr(head);
    if (util::get_at<std::uint32_t>(view(head + len + 4).data() + head + len) != util::calc_crc32(text))
      throw std::runtime_error(fmt::format("{}: damaged journal header", path_));
    if (text != campaign_text)
      throw JournalRefused(fmt::format("{} belongs to a different campaign (resolved campaign text differs); finish "
                                       "it with the same campaign file and --set options, or start over with --force",
                                       path_));
    skip(head + len + 4);
  }
  // A part's header. Throws unless it is `expected` (part_header()).
  void read_part_header(const std::string& expected) {
    if (!need(kPartHeader) || std::memcmp(view(sizeof kPartMagic).data(), kPartMagic, sizeof kPartMagic) != 0)
      throw std::runtime_error(fmt::format("{} is not a truss-campaign part journal", path_));
    const std::string_view h = view(kPartHeader);
    if (util::get_at<std::uint32_t>(h.data() + kPartHeader - 4) != util::calc_crc32(h.substr(0, kPartHeader - 4)))
      throw std::runtime_error(fmt::format("{}: damaged part journal header", path_));
    if (util::get_at<std::uint32_t>(h.data() + 8) != kVersion)
      throw std::runtime_error(fmt::format("{}: unreadable part journal header (version {}, this program writes {})",
                                           path_, util::get_at<std::uint32_t>(h.data() + 8), kVersion));
    if (h != expected)
      throw JournalRefused(fmt::format("{} is not a part of this campaign's journal (another campaign, session or "
                                       "rank); finish it with the same campaign file and --set options, or start "
                                       "over with --force", path_));
    skip(kPartHeader);
  }
  std::int64_t frames = 0, records = 0;  // good ones read so far

 private:
  int fd_;
  std::string path_;
  std::size_t size_;
  std::string buf_;
  std::size_t at_ = 0, offset_ = 0;
};

std::string JournalScan::describe(const std::string& path) const {
  if (dropped_bytes == 0) return "";
  if (!damaged_middle())
    return fmt::format("{}: torn last record dropped ({} bytes at byte {}); {} records kept", path, dropped_bytes,
                       damage_offset, records_kept);
  return fmt::format("{}: damaged in the middle at byte {}: {} records before the damage kept, {} valid records "
                     "after it dropped ({} bytes) and computed again", path, damage_offset, records_kept,
                     records_dropped, dropped_bytes);
}

Journal::Journal(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}

Journal::Journal(Journal&& o) noexcept
    : path_(std::move(o.path_)), fd_(o.fd_), buffer_(std::move(o.buffer_)), error_(std::move(o.error_)),
      reader_(std::move(o.reader_)) {
  o.fd_ = -1;
}

Journal::~Journal() {
  if (fd_ < 0) return;
  try {
    write_buffer();
  } catch (...) {
  }
  ::close(fd_);
}

Journal Journal::create(const std::string& path, const std::string& campaign_text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) fail_errno("cannot create journal", path);
  Journal j(path, fd);
  j.buffer_.assign(kMagic, sizeof kMagic);
  util::put(j.buffer_, kVersion);
  util::put(j.buffer_, static_cast<std::uint32_t>(campaign_text.size()));
  j.buffer_ += campaign_text;
  util::put(j.buffer_, util::calc_crc32(campaign_text));
  j.flush();
  return j;
}

std::string part_journal_path(const std::string& output, std::int64_t session, int rank) {
  return fmt::format("{}.journal.{}.{}", output, session, rank);
}

std::vector<std::string> remove_part_journals(const std::string& output) {
  const fs::path p(output);
  const fs::path dir = p.has_parent_path() ? p.parent_path() : fs::path(".");
  const std::string prefix = p.filename().string() + ".journal.";
  std::vector<std::string> removed;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() <= prefix.size() || name.rfind(prefix, 0) != 0) continue;
    const std::string rest = name.substr(prefix.size());  // SESSION.RANK, digits only
    const auto dot = rest.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == rest.size() ||
        rest.find_first_not_of("0123456789.") != std::string::npos || rest.find('.', dot + 1) != std::string::npos)
      continue;
    if (fs::remove(e.path(), ec)) removed.push_back(e.path().string());
  }
  return removed;
}

Journal Journal::create_part(const std::string& path, std::uint32_t campaign_crc, std::int64_t session, int rank) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) fail_errno("cannot create journal", path);
  Journal j(path, fd);
  j.buffer_ = part_header(campaign_crc, session, rank);
  j.flush();
  return j;
}

Journal Journal::open_part(const std::string& path, std::uint32_t campaign_crc, std::int64_t session, int rank) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) fail_errno("cannot open journal", path);
  Journal j(path, fd);
  const off_t size = ::lseek(fd, 0, SEEK_END);
  if (size < 0 || ::lseek(fd, 0, SEEK_SET) < 0) fail_errno("cannot seek journal", path);
  j.reader_ = std::make_unique<Reader>(fd, j.path_, static_cast<std::size_t>(size));
  j.reader_->read_part_header(part_header(campaign_crc, session, rank));
  return j;
}

Journal Journal::open_existing(const std::string& path, const std::string& campaign_text) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) fail_errno("cannot open journal", path);
  Journal j(path, fd);
  const off_t size = ::lseek(fd, 0, SEEK_END);
  if (size < 0 || ::lseek(fd, 0, SEEK_SET) < 0) fail_errno("cannot seek journal", path);
  j.reader_ = std::make_unique<Reader>(fd, j.path_, static_cast<std::size_t>(size));
  j.reader_->read_header(campaign_text);
  return j;
}

bool Journal::next_frame(FrameKind& kind, std::string_view& payload, std::size_t& offset) {
  if (!reader_) throw std::logic_error("Journal::next_frame: the journal is not being read");
  std::uint8_t k = 0;
  if (!reader_->frame_at(k, payload)) return false;
  kind = static_cast<FrameKind>(k);
  offset = reader_->offset();
  reader_->skip(kFrameHeader + payload.size());
  ++reader_->frames;
  reader_->records += kind == FrameKind::run;
  return true;
}

JournalScan Journal::finish_reading(std::size_t cut) {
  Reader& r = *reader_;
  JournalScan scan;
  scan.frames_kept = r.frames;
  scan.records_kept = r.records;
  if (cut <= r.offset()) {  // read up to a cut: the file ends there
    reader_.reset();
    if (::ftruncate(fd_, static_cast<off_t>(cut)) != 0) fail_errno("cannot truncate journal", path_);
    if (::lseek(fd_, static_cast<off_t>(cut), SEEK_SET) < 0) fail_errno("cannot seek journal", path_);
    return scan;
  }
  const std::size_t good = r.offset();
  scan.damage_offset = good;
  scan.dropped_bytes = r.left();
  // After the damage: count the frames that still pass, at any byte (their framing is lost).
  if (r.left() > 0) r.skip(1);
  std::uint8_t kind = 0;
  std::string_view payload;
  while (r.left() > 0) {
    if (r.frame_at(kind, payload)) {
      scan.records_dropped += kind == static_cast<std::uint8_t>(FrameKind::run);
      r.skip(kFrameHeader + payload.size());
    } else {
      r.skip(1);
    }
  }
  reader_.reset();
  if (scan.dropped_bytes > 0 && ::ftruncate(fd_, static_cast<off_t>(good)) != 0)
    fail_errno("cannot truncate journal", path_);
  if (::lseek(fd_, static_cast<off_t>(good), SEEK_SET) < 0) fail_errno("cannot seek journal", path_);
  return scan;
}

void Journal::append(FrameKind kind, std::string_view payload) {
  const std::size_t start = begin_frame(buffer_);
  buffer_.append(payload);
  seal_frame(buffer_, start, kind);
  if (buffer_.size() >= kWriteThrough) write_buffer();
}

void Journal::append_frame(std::string_view sealed_frame) {
  buffer_.append(sealed_frame);
  if (buffer_.size() >= kWriteThrough) write_buffer();
}

// After a failed write nothing more is written (a retry would leave valid frames after a torn
// one): every later call throws the same error.
void Journal::write_buffer() {
  if (!error_.empty()) throw std::runtime_error(error_);
  try {
    write_all(fd_, buffer_, path_);
  } catch (const std::runtime_error& e) {
    error_ = e.what();
    throw;
  }
  buffer_.clear();
}

void Journal::write_out() { write_buffer(); }

void Journal::flush() {
  write_buffer();
  if (::fdatasync(fd_) != 0) {
    error_ = fmt::format("cannot sync journal {}: {}", path_, std::strerror(errno));
    throw std::runtime_error(error_);
  }
}

// Not written out nor synced first: the results file, committed before, holds every record.
void Journal::close_and_remove() {
  buffer_.clear();
  ::close(fd_);
  fd_ = -1;
  if (::unlink(path_.c_str()) != 0) fail_errno("cannot remove journal", path_);
}

}  // namespace truss::results
