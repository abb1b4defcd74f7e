// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/stepGrowth.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <optional>
#include <string>

namespace asyncfem {

/// Per-step growth above which checkPaperCoupling() warns: the estimate of a step that
/// never gains energy stays below 1 + 1e-5 (stepGrowth.hpp: its Ritz values lie in the
/// numerical range, widened only by the rigid-mode weighting), and a growth of 1e-4 per
/// large step needs 3,500 large steps to double the energy.
inline constexpr double kStepGrowthWarningTolerance = 1e-4;

/// estimateStepGrowth() of the integrator scene names, built afresh by registry's
/// factory (the same options parse as the scene's own integrator) on
/// homogeneousLinearSystem(simulation.integrator->system()): the scene's mass, damping
/// and fixed DOFs, its force model's tangent at rest, no loads. Costs one factorization
/// and options.krylovDimension steps.
StepGrowthEstimate estimateSceneStepGrowth(const Scene& scene, const Simulation& simulation,
                                           const StepGrowthOptions& options = {},
                                           const IntegratorRegistry& registry = defaultIntegratorRegistry());

/// What checkPaperCoupling() found.
struct PaperCouplingCheck {
  StepGrowthEstimate estimate;
  /// Regions as "name (m = 64), ..." (every fast region of the integrator).
  std::string regions;
  /// Empty unless estimate.spectralRadius > 1 + kStepGrowthWarningTolerance: then a
  /// sentence naming the regions, m and the estimate and suggesting "coupling": "stable"
  /// or a smaller m.
  std::string warning;
};

/// When simulation's integrator may gain energy (RunReport::mayGainEnergy: the
/// asynchronous integrator with the paper's coupling, as constructed):
/// estimateSceneStepGrowth() and the warning. std::nullopt for every other integrator or
/// coupling, without any work.
std::optional<PaperCouplingCheck> checkPaperCoupling(const Scene& scene, const Simulation& simulation,
                                                     const IntegratorRegistry& registry = defaultIntegratorRegistry());

}  // namespace asyncfem
