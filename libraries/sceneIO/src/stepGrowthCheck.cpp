// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <sstream>

namespace asyncfem {

StepGrowthEstimate estimateSceneStepGrowth(const Scene& scene, const Simulation& simulation,
                                           const StepGrowthOptions& options, const IntegratorRegistry& registry) {
  const IntegratorFactory* factory = registry.find(scene.integrator.name);
  if (factory == nullptr)
    throw Error(scene.sourceName + ": integrator.name: unknown integrator " + scene.integrator.name);
  const std::unique_ptr<Integrator> integrator = (*factory)(
      scene, *simulation.mesh, homogeneousLinearSystem(simulation.integrator->system()), scene.integrator.options);
  return estimateStepGrowth(*integrator, options);
}

std::optional<PaperCouplingCheck> checkPaperCoupling(const Scene& scene, const Simulation& simulation,
                                                     const IntegratorRegistry& registry) {
  const auto* async = dynamic_cast<const AsyncBackwardEuler*>(simulation.integrator.get());
  if (async == nullptr || async->options().coupling != AsyncCoupling::paper) return std::nullopt;
  PaperCouplingCheck check;
  check.estimate = estimateSceneStepGrowth(scene, simulation, {}, registry);
  std::ostringstream regions;
  for (int i = 0; i < async->partition().numRegions(); ++i) {
    regions << (i > 0 ? ", " : "") << async->partition().region(i).name << " (m = " << async->partition().ratio(i)
            << ")";
  }
  check.regions = regions.str();
  if (check.estimate.spectralRadius > 1.0 + kStepGrowthWarningTolerance) {
    std::ostringstream warning;
    warning << scene.sourceName << ": integrator.options.coupling: the paper's coupling with regions " << check.regions
            << " is unstable here: one large step multiplies some state by about " << check.estimate.spectralRadius
            << " (spectral radius estimated from " << check.estimate.steps << " steps"
            << (check.estimate.converged ? "" : ", not converged") << "), so the run may gain energy and blow up; set "
            << "\"coupling\": \"stable\" or use a smaller m";
    check.warning = warning.str();
  }
  return check;
}

}  // namespace asyncfem
