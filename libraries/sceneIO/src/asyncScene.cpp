// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>

namespace asyncfem {

AsyncSettings parseAsyncOptions(const Scene& scene, const TetMesh& mesh, const FreeDofs& freeDofs,
                                const nlohmann::json& options) {
  IntegratorContext context = integratorContext(scene);
  // A non-owning pointer: the context lives only for this call.
  context.mesh = std::shared_ptr<const TetMesh>(&mesh, [](const TetMesh*) {});
  context.system.freeDofs = freeDofs;
  return parseAsyncSettings(context, options);
}

}  // namespace asyncfem
