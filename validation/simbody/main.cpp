// simbody-mast: deploys a truss-sim scene on the Simbody model of validation/simbody and prints
// the run as JSON (the field names of `truss-sim --json` where the quantity is the same).
//
//   simbody-mast SCENE.toml [--set table.key=value]... [--longerons 1|3] [--integrator rkm|rkf|rk3|cpodes]
//                [--accuracy A] [--max-time T_s] [--history FILE.csv]
// Exit status: 0 the mast deployed; 1 it did not (rail miss, time cap); 2 bad input; 3 Simbody failed.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "mast_run.hpp"
#include "scene.hpp"

namespace {
using namespace mastcheck;

std::string num(double x) {
  if (!std::isfinite(x)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

std::string peak_fields(const std::string& name, const Peak& p, bool with_bay) {
  const std::string stem = name.substr(0, name.size() - 2);  // drop the unit "_N"
  std::string out = "\"" + name + "\": " + num(p.value) + ", \"" + stem + "_time_s\": " + num(p.time_s);
  if (with_bay) out += ", \"" + stem + "_bay\": " + std::to_string(p.bay);
  return out;
}

void print_json(const MastScene& scene, const RunOptions& options, const RunSummary& r) {
  std::ostringstream o;
  o << "{\n  \"engine\": \"simbody\", \"longerons_per_bay\": " << options.longerons_per_bay
    << ", \"integrator\": \"" << options.integrator << "\", \"accuracy\": "
    << num(options.accuracy > 0 ? options.accuracy : scene.rtol) << ",\n";
  o << "  \"status\": \"" << r.status << "\", \"n_bays\": " << scene.n_bays << ", \"deploy_time_s\": "
    << num(r.deploy_time_s) << ", \"end_time_s\": " << num(r.end_time_s) << ",\n";
  o << "  " << peak_fields("peak_drive_force_N", r.drive_force_N, true) << ",\n";
  o << "  " << peak_fields("peak_pin_force_N", r.pin_force_N, true) << ",\n";
  o << "  " << peak_fields("peak_diagonal_tension_N", r.diagonal_tension_N, false) << ",\n";
  o << "  \"start_drive_impulse_Ns\": " << num(r.start_drive_impulse_Ns) << ", \"max_constraint_error\": "
    << num(r.max_constraint_error) << ",\n";
  o << "  \"steps\": " << r.steps << ", \"realizations\": " << r.realizations << ", \"wall_time_s\": "
    << num(r.wall_time_s) << ", \"cpu_time_s\": " << num(r.cpu_time_s) << ",\n  \"bays\": [\n";
  for (int i = 1; i <= scene.n_bays; ++i) {
    const BayRecord& b = r.bays[i];
    o << "    {\"bay\": " << i << ", \"entry_time_s\": " << num(b.entry_time_s) << ", \"lock_time_s\": "
      << num(b.lock_time_s) << ", \"latch_energy_J\": " << num(b.latch_energy_J)
      << ", \"entry_energy_loss_J\": " << num(b.entry_energy_loss_J) << ", \"entry_impulse_Ns\": "
      << num(b.entry_impulse_Ns) << ", \"entry_drive_impulse_Ns\": " << num(b.entry_drive_impulse_Ns) << ", "
      << peak_fields("peak_drive_force_N", b.drive_force_N, false) << ", "
      << peak_fields("peak_pin_force_N", b.pin_force_N, false) << "}" << (i < scene.n_bays ? ",\n" : "\n");
  }
  o << "  ]\n}\n";
  std::cout << o.str();
}

int usage(const std::string& why) {
  std::cerr << "error: " << why << "\nusage: simbody-mast SCENE.toml [--set table.key=value]... "
            << "[--longerons 1|3] [--integrator rkm|rkf|rk3|cpodes] [--accuracy A] [--max-time T_s] "
            << "[--history FILE.csv]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene_path;
  std::vector<std::string> overrides;
  RunOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--set" && has_value) overrides.push_back(argv[++i]);
    else if (arg == "--longerons" && has_value) options.longerons_per_bay = std::atoi(argv[++i]);
    else if (arg == "--integrator" && has_value) options.integrator = argv[++i];
    else if (arg == "--accuracy" && has_value) options.accuracy = std::atof(argv[++i]);
    else if (arg == "--max-time" && has_value) options.max_time_s = std::atof(argv[++i]);
    else if (arg == "--history" && has_value) options.history_path = argv[++i];
    else if (!arg.empty() && arg[0] != '-' && scene_path.empty()) scene_path = arg;
    else return usage("unexpected argument " + arg);
  }
  if (scene_path.empty()) return usage("no scene file");
  if (options.longerons_per_bay != 1 && options.longerons_per_bay != 3) return usage("--longerons must be 1 or 3");
  if (options.integrator != "rkm" && options.integrator != "rkf" && options.integrator != "rk3" &&
      options.integrator != "cpodes")
    return usage("--integrator must be rkm, rkf, rk3 or cpodes");
  if (!(options.max_time_s > 0)) return usage("--max-time must be positive");
  try {
    const MastScene scene = read_scene(scene_path, overrides);
    const RunSummary summary = run_deployment(scene, options);
    print_json(scene, options, summary);
    return summary.status == "ok" ? 0 : 1;
  } catch (const SceneError& e) {
    std::cerr << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {  // Simbody's exceptions (a failed step, a singular solve)
    std::cerr << "error: the Simbody run failed: " << e.what() << "\n";
    return 3;
  }
}
