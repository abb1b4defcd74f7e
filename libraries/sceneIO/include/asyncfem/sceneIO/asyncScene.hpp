// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/autoRegions.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// What `integrator.options` of an "async" scene says (docs/scene-format.md, section
/// "Asynchronous integrator").
struct AsyncSceneOptions {
  AsyncOptions solver;
  bool automaticRegions = false;
  AutoRegionOptions automatic;       ///< largeTimestep, frameRate from the scene; modalCheck on
  std::vector<AsyncRegion> regions;  ///< explicit regions, resolved on the mesh
};

/// Reads `integrator.options` of an async scene and resolves its regions on mesh; errors
/// name the key ("integrator.options.regions[1].ratio: ...").
AsyncSceneOptions parseAsyncOptions(const Scene& scene, const TetMesh& mesh, const FreeDofs& freeDofs,
                                    const nlohmann::json& options);

/// The registry factory for name "async": AsyncBackwardEuler with the scene's regions
/// (explicit, or "auto" through suggestRegions()).
IntegratorFactory asyncIntegratorFactory();

}  // namespace asyncfem
