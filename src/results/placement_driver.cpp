// The placement driver (placement_driver.hpp): sec2's POSIX I/O (H5FDsec2.c of HDF5 1.10: open
// flags, zero fill past the end of file, truncation to the end of allocation) with placed writes.
#include "results/placement_driver.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

static_assert(H5_VERS_MAJOR == 1 && H5_VERS_MINOR == 10, "the placement driver implements HDF5 1.10's H5FD_class_t");

namespace truss::results {

namespace {

constexpr haddr_t kMaxAddr = (haddr_t{1} << (8 * sizeof(off_t) - 1)) - 1;

struct DriverInfo {  // what the file access property list carries to open()
  PlacementState* state;
};

struct File {
  H5FD_t pub;  // first: HDF5 sees a File as its H5FD_t
  int fd;
  haddr_t eoa, eof;
  dev_t device;
  ino_t inode;
  PlacementState* state;
};

File* of(H5FD_t* f) { return reinterpret_cast<File*>(f); }
const File* of(const H5FD_t* f) { return reinterpret_cast<const File*>(f); }

// A failed system call onto HDF5's error stack, worded as HDF5's own drivers word it (the system's
// message quoted: io/h5_util.cpp shows it), and the failure's return code.
herr_t fail(const char* what, hid_t minor) {
  const int err = errno;
  H5Epush2(H5E_DEFAULT, __FILE__, what, __LINE__, H5E_ERR_CLS, H5E_IO, minor,
           "%s failed: errno = %d, error message = '%s'", what, err, std::strerror(err));
  return -1;
}

void* fapl_copy(const void* info) {
  auto* c = new (std::nothrow) DriverInfo;
  if (c) *c = *static_cast<const DriverInfo*>(info);
  return c;
}
herr_t fapl_free(void* info) {
  delete static_cast<DriverInfo*>(info);
  return 0;
}
void* fapl_get(H5FD_t* f) {
  const DriverInfo info{of(f)->state};
  return fapl_copy(&info);
}

H5FD_t* open_file(const char* name, unsigned flags, hid_t fapl, haddr_t maxaddr) {
  if (!name || !*name || maxaddr == 0 || maxaddr > kMaxAddr) return nullptr;
  const auto* info = static_cast<const DriverInfo*>(H5Pget_driver_info(fapl));
  if (!info || !info->state) return nullptr;
  int o = (H5F_ACC_RDWR & flags) ? O_RDWR : O_RDONLY;
  if (H5F_ACC_TRUNC & flags) o |= O_TRUNC;
  if (H5F_ACC_CREAT & flags) o |= O_CREAT;
  if (H5F_ACC_EXCL & flags) o |= O_EXCL;
  const int fd = ::open(name, o | O_CLOEXEC, 0666);
  if (fd < 0) return nullptr;
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    ::close(fd);
    return nullptr;
  }
  auto* f = new (std::nothrow) File{};
  if (!f) {
    ::close(fd);
    return nullptr;
  }
  f->fd = fd;
  f->eof = static_cast<haddr_t>(st.st_size);
  f->device = st.st_dev;
  f->inode = st.st_ino;
  f->state = info->state;
  return &f->pub;
}

herr_t close_file(H5FD_t* h) {
  File* f = of(h);
  const int r = ::close(f->fd);
  delete f;
  return r == 0 ? 0 : fail("file close", H5E_CANTCLOSEFILE);
}

int compare(const H5FD_t* a, const H5FD_t* b) {
  const File *x = of(a), *y = of(b);
  if (x->device != y->device) return x->device < y->device ? -1 : 1;
  if (x->inode != y->inode) return x->inode < y->inode ? -1 : 1;
  return 0;
}

// sec2's features but those that buffer raw data or share a block of it: the metadata accumulator
// (a raw-data write that overlaps it is copied into it), the small-data block (small raw allocations
// share a block that HDF5 may write whole) and the sieve buffer. A placed chunk then lies in space
// of its own, and no buffer holds a copy of bytes the driver never wrote.
herr_t query(const H5FD_t*, unsigned long* flags) {
  *flags = H5FD_FEAT_AGGREGATE_METADATA | H5FD_FEAT_POSIX_COMPAT_HANDLE | H5FD_FEAT_DEFAULT_VFD_COMPATIBLE;
  return 0;
}

haddr_t get_eoa(const H5FD_t* f, H5FD_mem_t) { return of(f)->eoa; }
herr_t set_eoa(H5FD_t* f, H5FD_mem_t, haddr_t a) {
  of(f)->eoa = a;
  return 0;
}
haddr_t get_eof(const H5FD_t* f, H5FD_mem_t) { return of(f)->eof; }
herr_t get_handle(H5FD_t* f, hid_t, void** handle) {
  *handle = &of(f)->fd;
  return 0;
}

bool bad_region(haddr_t addr, size_t size) {
  return addr == HADDR_UNDEF || addr > kMaxAddr || size > kMaxAddr || addr + size > kMaxAddr;
}

herr_t read(H5FD_t* h, H5FD_mem_t, hid_t, haddr_t addr, size_t size, void* buf) {
  if (bad_region(addr, size)) return fail("file read (address overflow)", H5E_READERROR);
  auto* p = static_cast<unsigned char*>(buf);
  while (size > 0) {
    const ssize_t n = ::pread(of(h)->fd, p, size, static_cast<off_t>(addr));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return fail("file read", H5E_READERROR);
    if (n == 0) {  // past the end of the file, not of the allocation: zeros
      std::memset(p, 0, size);
      break;
    }
    size -= static_cast<size_t>(n);
    addr += static_cast<haddr_t>(n);
    p += n;
  }
  return 0;
}

herr_t write(H5FD_t* h, H5FD_mem_t type, hid_t, haddr_t addr, size_t size, const void* buf) {
  File* f = of(h);
  if (bad_region(addr, size)) return fail("file write (address overflow)", H5E_WRITEERROR);
  if (type == H5FD_MEM_DRAW && buf == Placement::kBytes && f->state->placing()) {
    f->state->record(addr, size);
    return 0;
  }
  const auto* p = static_cast<const unsigned char*>(buf);
  while (size > 0) {
    const ssize_t n = ::pwrite(f->fd, p, size, static_cast<off_t>(addr));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return fail("file write", H5E_WRITEERROR);
    size -= static_cast<size_t>(n);
    addr += static_cast<haddr_t>(n);
    p += n;
  }
  if (addr > f->eof) f->eof = addr;
  return 0;
}

// To the end of allocation, as sec2 does at a flush or close: placed chunks lie inside it.
herr_t truncate(H5FD_t* h, hid_t, hbool_t) {
  File* f = of(h);
  if (f->eoa == f->eof) return 0;
  if (::ftruncate(f->fd, static_cast<off_t>(f->eoa)) != 0) return fail("file truncate", H5E_SEEKERROR);
  f->eof = f->eoa;
  return 0;
}

const H5FD_class_t kClass = {
    "truss_placement", kMaxAddr, H5F_CLOSE_WEAK,
    nullptr, nullptr, nullptr, nullptr,           // terminate, superblock (none: readers use sec2)
    sizeof(DriverInfo), fapl_get, fapl_copy, fapl_free,
    0, nullptr, nullptr,                          // no transfer properties
    open_file, close_file, compare, query,
    nullptr, nullptr, nullptr,                    // type map, alloc, free: HDF5's own
    get_eoa, set_eoa, get_eof, get_handle, read, write,
    nullptr, truncate, nullptr, nullptr,          // flush (nothing buffered), lock (the output's own lock)
    H5FD_FLMAP_DICHOTOMY};

hid_t driver_id() {
  static const hid_t id = H5FDregister(&kClass);
  if (id < 0) throw std::runtime_error("cannot register the results file's HDF5 driver");
  return id;
}

}  // namespace

hid_t make_placement_fapl(PlacementState& state) {
  const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl < 0) throw std::runtime_error("cannot create a file access property list");
  const DriverInfo info{&state};
  if (H5Pset_driver(fapl, driver_id(), &info) < 0) {
    H5Pclose(fapl);
    throw std::runtime_error("cannot select the results file's HDF5 driver");
  }
  return fapl;
}

const char Placement::kBytes[1] = {0};

Placement::Placement(PlacementState& s) : s_(s), recorded0_(s.recorded_) { s_.placing_ = true; }
Placement::~Placement() { s_.placing_ = false; }

ChunkAddress Placement::address() const {
  if (s_.recorded_ != recorded0_ + 1)
    throw std::runtime_error(fmt::format("placing a chunk: HDF5 issued {} raw-data writes, not one",
                                         s_.recorded_ - recorded0_));
  return s_.last_;
}

}  // namespace truss::results
