// Benchmark (not a test): one free-stack deployment (the 30-bay slack scene, contacts off, as the
// rare-failure campaign runs it) timed right after an ISA-L CRC-32 of a 4.7 kB record (the frame
// every run seals), three ways, interleaved, thread CPU time, medians:
//   plain:       no ISA-L call before the run;
//   dirty:       crc32_gzip_refl called directly (its vector kernel leaves the upper halves of the
//                vector registers dirty);
//   cleared:     util::calc_crc32, which clears them after the kernel (util/isal.hpp).
// Usage: bench_vector_state SCENE.toml [REPEATS]
#include <isa-l/crc.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "io/scene_toml.hpp"
#include "sim/simulate.hpp"
#include "util/isal.hpp"

using namespace truss;

namespace {
double cpu_now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_vector_state SCENE.toml [REPEATS]\n");
    return 2;
  }
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 11;
  const sim::SceneOptions scene = io::parse_scene_file(
      argv[1], {"run.output_step_s=0", "stack.contacts=false", "mast.diagonal_free_length_m=0.49"});
  const std::string record(4700, 'x');
  std::vector<double> plain, dirty, cleared;
  long sink = 0;
  for (int r = 0; r < repeats; ++r) {
    double t0 = cpu_now();
    sink += sim::simulate(scene).steps;
    plain.push_back(cpu_now() - t0);
    sink += crc32_gzip_refl(0, reinterpret_cast<const unsigned char*>(record.data()), record.size());
    t0 = cpu_now();
    sink += sim::simulate(scene).steps;
    dirty.push_back(cpu_now() - t0);
    sink += util::calc_crc32(record);
    t0 = cpu_now();
    sink += sim::simulate(scene).steps;
    cleared.push_back(cpu_now() - t0);
  }
  std::printf("free-stack run (ms of thread CPU, median of %d): plain %.2f | after ISA-L's CRC %.2f | after "
              "util::calc_crc32 %.2f | dirty/plain %.2f, cleared/plain %.2f (checksum %ld)\n",
              repeats, 1e3 * median(plain), 1e3 * median(dirty), 1e3 * median(cleared),
              median(dirty) / median(plain), median(cleared) / median(plain), sink);
}
