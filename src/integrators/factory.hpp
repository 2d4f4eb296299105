// The one place that maps run.integrator to an Integrator (the stage loop asks for one per run).
#pragma once
#include <memory>

#include "integrators/ode.hpp"

namespace truss::integrators {

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const IntegratorOptions& io);

}  // namespace truss::integrators
