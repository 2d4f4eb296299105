// truss_deploy._core: the module's entry point (bindings.hpp).
#include "bindings.hpp"

PYBIND11_MODULE(_core, m) {
  m.doc() = "The truss-deploy simulator (sim::simulate, the scene key table, the summary's field tables).";
  truss::py::bind_scene(m);
  truss::py::bind_result(m);
  truss::py::bind_many(m);
  m.attr("version") = TRUSS_VERSION;       // the project's version, as truss-sim --version prints it
  m.attr("git_revision") = TRUSS_GIT_REV;  // the commit the binaries were built from
  m.attr("run_status_names") = [] {
    pybind11::list names;
    for (int i = 0; i < truss::sim::kRunStatusCount; ++i)
      names.append(truss::sim::to_string(static_cast<truss::sim::RunStatus>(i)));
    return names;
  }();
}
