// truss-sim: one deployment (or retraction) of a folding truss mast from a scene file.
//
//   truss-sim SCENE.toml [-o OUT.h5] [--set table.key=value]... [--json] [--force]
//
// Exit status: 0 the run ended ok; 1 the run failed physically (stall, rail miss, ...: the output
// file is still written, a failed run is data); 2 bad input (command line, scene, existing output
// file), nothing written; 3 the output file could not be written, or an internal error.
#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <csignal>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "io/build_info.hpp"
#include "io/h5_output.hpp"
#include "io/json_summary.hpp"
#include "io/scene_toml.hpp"
#include "sim/simulate.hpp"


namespace {
constexpr int kExitOk = 0;
constexpr int kExitRunFailed = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitInternal = 3;
}  // namespace

int main(int argc, char** argv) {
  // A write past the file-size limit (ulimit -f) fails with EFBIG, which the output code reports
  // (exit 3, temporary file removed), instead of killing the process with SIGXFSZ mid-write.
  std::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"Simulates the deployment (or retraction) of a folding truss mast.", "truss-sim"};
  std::string scene_path;
  std::string out_path;
  std::vector<std::string> overrides;
  bool json = false;
  bool force = false;
  app.add_option("scene", scene_path, "Scene file (TOML), e.g. campaigns/scenes/table1.toml")
      ->required();
  auto* out_opt = app.add_option("-o,--output", out_path, "Write the run to this HDF5 file (docs/hdf5-schema.md)");
  app.add_option("--set", overrides,
                 "Override a scene key, e.g. --set mast.n_bays=12 --set drive.mode=motor "
                 "(repeatable; the value is read as a TOML value, a bare word as a string)")
      ->type_name("KEY=VALUE")
      ->expected(1)
      ->allow_extra_args(false)  // one value per --set: a scene path after it stays positional
      ->take_all();
  app.add_flag("--json", json, "Print the run summary as JSON on stdout");
  app.add_flag("--force", force, "Overwrite the output file if it exists");
  app.set_version_flag("--version", fmt::format("truss-sim {} ({})", truss::io::get_software_version(),
                                                truss::io::get_git_revision()));
  app.footer(
      "Exit status: 0 ok; 1 the run failed physically (stall, rail miss, ...; the output file is "
      "still written); 2 bad input, nothing written; 3 output could not be written or internal "
      "error.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);  // prints help, version or the error
    return rc == 0 ? kExitOk : kExitBadInput;
  }

  truss::sim::SceneOptions scene;
  const bool write_output = out_opt->count() > 0;  // -o "" is an error, not "no output"
  try {
    std::vector<std::string> warnings;
    scene = truss::io::parse_scene_file(scene_path, overrides, &warnings);
    for (const auto& w : warnings) std::cerr << w << '\n';
    if (write_output) truss::io::check_output_path(out_path, force);  // before simulating
  } catch (const truss::io::InputError& e) {
    std::cerr << e.what() << '\n';
    return kExitBadInput;
  }

  truss::sim::RunResult r;
  try {
    r = truss::sim::simulate(scene);
  } catch (const std::exception& e) {
    std::cerr << "error: " << scene_path << ": internal error in the simulation: " << e.what()
              << '\n';
    return kExitInternal;
  }
  if (r.status == truss::sim::RunStatus::invalid_input) {
    std::cerr << "error: " << scene_path << ": " << r.message << '\n';
    return kExitBadInput;
  }

  if (write_output) {
    try {
      truss::io::write_run_h5(out_path, r, truss::io::resolved_scene_toml(scene), force);
    } catch (const truss::io::InputError& e) {
      std::cerr << e.what() << '\n';
      return kExitBadInput;
    } catch (const std::exception& e) {
      std::cerr << "error: cannot write " << out_path << ": " << e.what() << '\n';
      return kExitInternal;
    }
  }

  if (json) {
    std::cout << truss::io::to_json(r);
  } else {
    std::string text = r.to_string();
    if (text.empty() || text.back() != '\n') text += '\n';
    std::cout << text;
  }
  std::cout.flush();
  if (r.status != truss::sim::RunStatus::ok) {
    std::cerr << "truss-sim: run ended with status '" << truss::sim::to_string(r.status) << "'"
              << (r.message.empty() ? "" : ": " + r.message) << '\n';
    return kExitRunFailed;
  }
  return kExitOk;
}
