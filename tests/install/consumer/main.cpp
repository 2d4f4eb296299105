// Uses the installed library: parses a scene, simulates it, and evaluates one sampling function.
// Prints "status peak_drive_force_N deploy_time_s normal_quantile(0.975)" on one line.
#include <cstdio>
#include <exception>

#include "sampling/sampling.hpp"
#include "io/scene_toml.hpp"
#include "sim/simulate.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer SCENE.toml\n");
    return 2;
  }
  try {
    const truss::sim::SceneOptions scene = truss::io::parse_scene_file(argv[1], {"mast.n_bays=4"});
    const truss::sim::RunResult r = truss::sim::simulate(scene);
    std::printf("%s %.17g %.17g %.17g\n", truss::sim::to_string(r.status), r.peak_drive_force_N, r.deploy_time_s,
                truss::sampling::normal_quantile(0.975));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
