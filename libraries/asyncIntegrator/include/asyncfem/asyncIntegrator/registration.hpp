// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/asyncIntegrator/runTimeRegions.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// What the options object of an "async" (or "multirate-uncoupled") integrator says
/// (docs/scene-format.md, section "Asynchronous integrator"), with its regions resolved
/// on the context's mesh.
struct AsyncSettings {
  AsyncOptions solver;
  bool automaticRegions = false;
  RegionProposalOptions automatic;   ///< largeTimestep and frameRate from the context; modalCheck on
  std::vector<AsyncRegion> regions;  ///< explicit regions, or those the region proposal kept
  /// The region proposal (regions "auto"), for reports: what was proposed, withdrawn, why.
  std::optional<RegionProposal> proposal;
  /// Run-time regions ("regions": {"adaptive": {...}}): the policy, and the object as given
  /// (written back by asyncSettingsJson).
  std::optional<RunTimeRegionOptions> adaptive;
  nlohmann::json adaptiveSource;
  /// The partition of the regions, built once on the context's mesh and free DOFs (its
  /// errors name the "regions" key); partition->touching(): the regions touch or nest, so
  /// AsyncBackwardEuler runs its hierarchy solve (chooseStepSolver()).
  std::optional<RegionPartition> partition;
};

/// The option keys "async" reads.
const std::vector<std::string>& asyncOptionKeys();

/// The proposed-region settings an "async" options object gives: hL and the frame rate
/// from the context, modal check on, then its "auto" object (target, growLayers,
/// maxRatio, modalCheck; other keys are errors naming them). What "regions": "auto" runs
/// with, for tools that propose regions the way the simulator would.
RegionProposalOptions parseRegionProposalOptions(const IntegratorContext& context, const nlohmann::json& options);

/// Reads options (a JSON object) as "async" does; errors name the key under
/// context.optionsPath ("integrator.options.regions[1].ratio: ..."). Regions "auto" (the
/// default) runs proposeRegions() with the modal check on the context's mesh and mass type.
AsyncSettings parseAsyncSettings(const IntegratorContext& context, const nlohmann::json& options);

/// The other direction: the options object that parseAsyncSettings() reads back to the same
/// solver options and regions. Solver keys are written only where they differ from
/// AsyncOptions' defaults (so an object with regions alone is also valid for
/// "multirate-uncoupled"); the regions are always written explicitly (asyncRegionsJson),
/// automatic ones as the regions they resolved to, so the object reproduces the run
/// without running the proposal again.
nlohmann::json asyncSettingsJson(const AsyncSettings& settings);

/// One region as an element of "regions": {"name": ..., "ratio": m_i, "vertices": [0-based
/// ids]}; parseAsyncSettings() reads it back to the same region (vertices sorted, unique).
nlohmann::json asyncRegionJson(const AsyncRegion& region);

/// The "regions" array of these regions (asyncRegionJson of each, in order).
nlohmann::json asyncRegionsJson(const std::vector<AsyncRegion>& regions);

/// The largest ratio m_i = hL / hS_i of the regions, so hL / largestRatio() is the smallest
/// step any of them takes; 1 when there are none (everything runs at hL).
int largestRatio(const std::vector<AsyncRegion>& regions);

/// Adjusts or refuses (by throwing ValidationError) the settings of each "async" integrator
/// a registry builds, after they are read from the scene: e.g. the PETSc backend sets
/// AsyncOptions::Processes::largeSystemSolver (which chooseStepSolver() then refuses for regions that
/// touch or nest, naming the option).
/// The context is the integrator's (its mesh, system, timestep).
using AsyncSettingsHook = std::function<void(AsyncSettings&, const IntegratorContext&)>;

/// Adds "async" (AsyncBackwardEuler), "multirate-uncoupled" (UncoupledMultirate) and
/// "schroeder2011" (Schroeder2011); "async" runs asyncHook (when given) on its settings.
void registerMultirateIntegrators(IntegratorRegistry& registry, AsyncSettingsHook asyncHook = {});

}  // namespace asyncfem
