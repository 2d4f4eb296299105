// The vector state after ISA-L's kernels (util/isal.hpp): ISA-L's CRC-32, DEFLATE and Adler-32
// return with the upper halves of the vector registers dirty; every function of the wrapper, and so
// the chunk codec that calls it, must leave them clean, or the model's scalar SSE2 code that follows
// runs 2-3 times slower (bench/bench_vector_state). Checked without timing, by the processor's own record of which
// state components are in use: XGETBV with ECX = 1 (XINUSE), bit 2 (the upper 128 bits of YMM0-15)
// and bit 6 (the upper 256 bits of ZMM0-15) are 0 when that state is in its initial, clean
// configuration (Intel SDM vol. 1, 13.6 "Processor tracking of XSAVE-managed state").
#include <catch2/catch.hpp>

#include <cpuid.h>
#include <isa-l/crc.h>
#include <isa-l/igzip_lib.h>

#include <cstdint>
#include <optional>
#include <string>

#include "results/chunk_codec.hpp"
#include "util/isal.hpp"

namespace {

constexpr std::uint64_t kUpperHalves = (1u << 2) | (1u << 6);  // YMM_Hi128, ZMM_Hi256

bool has_xinuse() {  // CPUID.(EAX=0DH, ECX=1):EAX[2]: XGETBV with ECX = 1
  unsigned a = 0, b = 0, c = 0, d = 0;
  return __get_cpuid_count(0xD, 1, &a, &b, &c, &d) && ((a >> 2) & 1u);
}

std::uint64_t read_xinuse() {
  std::uint32_t lo = 0, hi = 0;
  asm volatile("xgetbv" : "=a"(lo), "=d"(hi) : "c"(1));
  return (static_cast<std::uint64_t>(hi) << 32) | lo;
}

std::string make_record() {  // a record-like buffer: mostly repeated, some varying bytes
  std::string s(4700, '\0');
  for (std::size_t i = 0; i < s.size(); ++i) s[i] = static_cast<char>((i * 2654435761u >> 13) & (i % 7 ? 0x0f : 0xff));
  return s;
}

}  // namespace

TEST_CASE("ISA-L's kernels leave the vector state clean behind the project's wrappers", "[util][vector_state]") {
  if (!has_xinuse()) {
    WARN("this CPU does not report XINUSE (XGETBV with ECX = 1): the vector state cannot be read here");
    return;
  }
  const std::string record = make_record();
  const auto* bytes = reinterpret_cast<const unsigned char*>(record.data());
  // ISA-L's own kernels, called directly, dirty the state (on this CPU Adler-32 and DEFLATE do, and
  // CRC-32 does on AVX-512 ones); XINUSE is read right after each call, before any other code (Catch's
  // own, glibc's AVX2 string functions) can clear it, and a wrapper must leave it clean whatever its
  // own kernel does.
  auto dirty = [&] {
    (void)crc32_gzip_refl(0, bytes, record.size());
    (void)isal_adler32(1, bytes, record.size());
    return read_xinuse();
  };
  auto check_clean = [&](const char* what, auto&& call) {
    const std::uint64_t before = dirty();
    call();
    const std::uint64_t after = read_xinuse();
    INFO(what << ": XINUSE 0x" << std::hex << before << " after ISA-L's own kernels, 0x" << after << " after the wrapper");
    if ((before & kUpperHalves) == 0) WARN("ISA-L's kernels leave the upper halves clean on this CPU: nothing to clear");
    CHECK((after & kUpperHalves) == 0);
  };
  std::uint32_t crc = 0, adler = 0;
  check_clean("util::calc_crc32", [&] { crc = truss::util::calc_crc32(record); });
  CHECK(crc == crc32_gzip_refl(0, bytes, record.size()));
  check_clean("util::calc_adler32", [&] { adler = truss::util::calc_adler32(bytes, record.size()); });
  CHECK(adler == isal_adler32(1, bytes, record.size()));
  truss::util::Deflater d;
  std::string out(2 * record.size() + 64, '\0');
  for (int level = 1; level <= 3; ++level) {
    std::optional<std::size_t> n;
    check_clean("util::Deflater", [&] { n = d.deflate(bytes, record.size(), level, reinterpret_cast<unsigned char*>(out.data()), out.size()); });
    CHECK(n.has_value());
  }
  truss::results::ChunkCodec codec;
  check_clean("the chunk codec (shuffle, DEFLATE, Adler-32)", [&] { codec.encode(record, 8, 1, out); });
  CHECK(!out.empty());
}
