// truss_deploy._core: the module's entry point (bindings.hpp).
#include "bindings.hpp"
#include "io/build_info.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "The truss-deploy simulator (sim::simulate, the scene key table, the summary's field tables).";
  truss::py::bind_scene(m);
  truss::py::bind_result(m);
  truss::py::bind_many(m);
  // The build's identity, as truss-sim --version prints it (io/build_info.hpp).
  m.attr("version") = std::string(truss::io::get_software_version());
  m.attr("git_revision") = std::string(truss::io::get_git_revision());
  m.attr("run_status_names") = [] {
    pybind11::list names;
    for (int i = 0; i < truss::sim::kRunStatusCount; ++i)
      names.append(truss::sim::to_string(static_cast<truss::sim::RunStatus>(i)));
    return names;
  }();
}
