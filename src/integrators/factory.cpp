#include "integrators/factory.hpp"

#include "integrators/auto_integrator.hpp"
#include "integrators/cvode_integrator.hpp"
#include "integrators/dop853.hpp"
#include "integrators/dopri54.hpp"
#include "integrators/ida_integrator.hpp"

namespace truss::integrators {

std::unique_ptr<Integrator> make_integrator(IntegratorKind kind, const IntegratorOptions& io) {
  switch (kind) {
    case IntegratorKind::cvode: return std::make_unique<CvodeIntegrator>(io, CvodeMethod::bdf);
    case IntegratorKind::cvode_adams: return std::make_unique<CvodeIntegrator>(io, CvodeMethod::adams);
    case IntegratorKind::automatic: return std::make_unique<AutoIntegrator>(io);
    case IntegratorKind::ida: return std::make_unique<IdaIntegrator>(io);
    case IntegratorKind::dop853: return std::make_unique<Dop853>(io);
    case IntegratorKind::dopri54: break;
  }
  return std::make_unique<DormandPrince54>(io);
}

}  // namespace truss::integrators
