// The vector state after ISA-L's kernels (util/vector_state.hpp): ISA-L's CRC-32, DEFLATE and
// Adler-32 return with the upper halves of the vector registers dirty; util::calc_crc32 and the
// chunk codec must leave them clean, or the model's scalar SSE2 code that follows runs 2-3 times
// slower (bench/bench_vector_state). Checked without timing, by the processor's own record of which
// state components are in use: XGETBV with ECX = 1 (XINUSE), bit 2 (the upper 128 bits of YMM0-15)
// and bit 6 (the upper 256 bits of ZMM0-15) are 0 when that state is in its initial, clean
// configuration (Intel SDM vol. 1, 13.6 "Processor tracking of XSAVE-managed state").
#include <catch2/catch.hpp>

#include <cpuid.h>
#include <isa-l/crc.h>

#include <cstdint>
#include <string>

#include "results/chunk_codec.hpp"
#include "util/crc32.hpp"

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
  // The raw kernel on this machine: if it dirties the state, the wrappers below must clean it.
  const std::uint32_t raw = crc32_gzip_refl(0, reinterpret_cast<const unsigned char*>(record.data()), record.size());
  const std::uint64_t after_raw = read_xinuse();
  INFO("XINUSE after ISA-L's own CRC-32: 0x" << std::hex << after_raw);
  SECTION("util::calc_crc32") {
    CHECK(truss::util::calc_crc32(record) == raw);
    CHECK((read_xinuse() & kUpperHalves) == 0);
  }
  SECTION("the chunk codec (shuffle, DEFLATE, Adler-32)") {
    truss::results::ChunkCodec codec;
    std::string out;
    (void)crc32_gzip_refl(0, reinterpret_cast<const unsigned char*>(record.data()), record.size());  // dirty again
    codec.encode(record, 8, 1, out);
    CHECK(!out.empty());
    CHECK((read_xinuse() & kUpperHalves) == 0);
  }
}
