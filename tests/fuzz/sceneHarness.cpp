// SPDX-License-Identifier: BSD-3-Clause
// The scene harness (sceneIO, and through it every integrator), apart from the file
// readers of harnesses.cpp so that those can be replayed without it (fileHarnesses()).
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>

#include "harnessSupport.hpp"
#include "harnesses.hpp"

namespace asyncfem::fuzz {

namespace {

// A box generator of at most 64 cells: built in milliseconds, so fuzzing stays fast and no
// input can ask the harness for a huge mesh (beams and mesh files are parsed only).
bool smallGeneratedMesh(const Scene& scene) {
  constexpr long long kMaxCells = 64;
  if (scene.mesh.source != Scene::MeshSource::box) return false;
  const Eigen::Vector3i& cells = scene.mesh.box.cells;
  return cells.minCoeff() > 0 && static_cast<long long>(cells.x()) * cells.y() * cells.z() <= kMaxCells;
}

}  // namespace

Outcome sceneOutcome(const std::uint8_t* data, std::size_t size) {
  return classify([&] {
    // Relative paths in the scene (mesh files, .bou files) resolve against the scratch folder.
    const Scene scene = loadScene(writeInput("fuzz.json", data, size));
    if (!smallGeneratedMesh(scene)) return "integrator " + scene.integrator.name + " (parsed only)";
    // Small generated meshes are built too, so that what parseScene passes on unread
    // reaches its readers: the integrator's options (async regions, adaptive policies,
    // reuseFactor, ...), the force model's options and the fixed and loaded vertices.
    const Simulation simulation = buildSimulation(scene);
    return "integrator " + simulation.integrator->name() + ", built with " +
           std::to_string(simulation.mesh->numVertices()) + " vertices";
  });
}

int fuzzScene(const std::uint8_t* data, std::size_t size) {
  abortOnCrash(sceneOutcome(data, size));
  return 0;
}

std::vector<Harness> allHarnesses() {
  std::vector<Harness> harnesses = fileHarnesses();
  harnesses.push_back({"scene", {{"scene", sceneOutcome}}});
  return harnesses;
}

}  // namespace asyncfem::fuzz
