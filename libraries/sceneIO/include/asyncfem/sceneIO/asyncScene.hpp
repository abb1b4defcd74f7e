// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <nlohmann/json.hpp>

namespace asyncfem {

/// parseAsyncSettings() for a scene's async options (mesh and free DOFs as the scene
/// builds them): what proposeRegions and the benchmark utilities use to see the regions
/// the simulator would run, without building an integrator.
AsyncSettings parseAsyncOptions(const Scene& scene, const TetMesh& mesh, const FreeDofs& freeDofs,
                                const nlohmann::json& options);

}  // namespace asyncfem
