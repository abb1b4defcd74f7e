// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/sceneIO/stepGrowthCheck.hpp>
#include <sstream>

namespace asyncfem {

StepGrowthEstimate estimateSceneStepGrowth(const Scene& scene, const Simulation& simulation,
                                           const StepGrowthOptions& options, const IntegratorRegistry& registry) {
  IntegratorContext context = integratorContext(scene);
  context.mesh = simulation.mesh;
  context.system = homogeneousLinearSystem(simulation.integrator->system());
  const std::unique_ptr<Integrator> integrator =
      registry.create(scene.integrator.name, std::move(context), scene.integrator.options);
  return estimateStepGrowth(*integrator, options);
}

std::optional<PaperCouplingCheck> checkPaperCoupling(const Scene& scene, const Simulation& simulation,
                                                     const IntegratorRegistry& registry) {
  if (!simulation.integrator->report().mayGainEnergy) return std::nullopt;
  PaperCouplingCheck check;
  check.estimate = estimateSceneStepGrowth(scene, simulation, {}, registry);
  std::ostringstream regions;
  bool first = true;
  for (const RegionSummary& region : regionSummaries(*simulation.integrator)) {
    regions << (first ? "" : ", ") << region.name << " (m = " << region.ratio << ")";
    first = false;
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
