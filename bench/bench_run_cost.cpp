// Benchmark helper (not a test): the C++ cost of one run as truss-sim and the Python module make it
// (sim::simulate(scene), the mast built inside the call), for bench/bench_python.py's side-by-side
// ratios. Usage: bench_run_cost SCENE.toml RUNS [table.key=value ...]
// Prints the mean wall time and the mean process CPU time per run in seconds over RUNS runs (one
// more runs first, untimed). CPU time is the steadier figure on a shared machine.
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/scene_toml.hpp"
#include "sim/simulate.hpp"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_run_cost SCENE.toml RUNS [table.key=value ...]\n");
    return 2;
  }
  const std::vector<std::string> overrides(argv + 3, argv + argc);
  truss::sim::SceneOptions scene;
  try {
    scene = truss::io::parse_scene_file(argv[1], overrides);
  } catch (const truss::io::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  const long runs = std::atol(argv[2]);
  double sink = truss::sim::simulate(scene).deploy_time_s;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  for (long i = 0; i < runs; ++i) sink += truss::sim::simulate(scene).deploy_time_s;
  const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("%.9e %.9e %g\n", s / static_cast<double>(runs), cpu / static_cast<double>(runs), sink);
  return 0;
}
