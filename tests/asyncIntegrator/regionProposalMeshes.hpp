// SPDX-License-Identifier: BSD-3-Clause
// Meshes the proposed-region tests propose regions on.
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

namespace asyncfem::test {

// The design note's antenna on a block, coarsely: a 0.5 x 0.5 x 0.2 block (rho 1000) with a
// 0.1 x 0.1 x 0.6 rod (rho 50, same E) standing on it, 0.1 m cells. makeBoxMesh cuts the
// whole 0.5 x 0.5 x 0.8 box; the elements outside block and rod are dropped here.
inline TetMesh antennaOnBlock() {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(0.5, 0.5, 0.8);
  spec.cells = Eigen::Vector3i(5, 5, 8);
  spec.material = Material{"void", 1.0, 1.0, 0.3};
  spec.regions.push_back(
      {"block", Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(2, 2, 0.2), {"block", 1000.0, 1e6, 0.3}});
  spec.regions.push_back(
      {"rod", Eigen::Vector3d(0.2, 0.2, 0.2), Eigen::Vector3d(0.3, 0.3, 2), {"rod", 50.0, 1e6, 0.3}});
  const TetMesh box = makeBoxMesh(spec);
  std::vector<int> newId(static_cast<std::size_t>(box.numVertices()), -1);
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector4i> elements;
  std::vector<int> elementMaterials;
  for (int e = 0; e < box.numElements(); ++e) {
    if (box.elementMaterial(e).name == "void") continue;
    Eigen::Vector4i element;
    for (int a = 0; a < 4; ++a) {
      int& id = newId[static_cast<std::size_t>(box.elements()(a, e))];
      if (id < 0) {
        id = static_cast<int>(positions.size());
        positions.push_back(box.restPosition(box.elements()(a, e)));
      }
      element[a] = id;
    }
    elements.push_back(element);
    elementMaterials.push_back(box.elementMaterial(e).name == "rod" ? 1 : 0);
  }
  Eigen::Matrix3Xd restPositions(3, static_cast<Eigen::Index>(positions.size()));
  for (std::size_t v = 0; v < positions.size(); ++v) restPositions.col(static_cast<Eigen::Index>(v)) = positions[v];
  Eigen::Matrix4Xi elementMatrix(4, static_cast<Eigen::Index>(elements.size()));
  for (std::size_t e = 0; e < elements.size(); ++e) elementMatrix.col(static_cast<Eigen::Index>(e)) = elements[e];
  return TetMesh(restPositions, elementMatrix, {{"block", 1000.0, 1e6, 0.3}, {"rod", 50.0, 1e6, 0.3}},
                 elementMaterials);
}

/// The mesh with its vertices below height z (rest positions) clamped.
inline FreeDofs clampedBelow(const TetMesh& mesh, double z) {
  std::vector<int> bottom;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).z() < z) bottom.push_back(v);
  return FreeDofs::fromFixedVertices(mesh.numVertices(), bottom);
}

/// The modal check on the antenna on a block: hL = 1/60 s, 30 frames/s.
inline RegionProposalOptions antennaModalOptions() {
  RegionProposalOptions options;
  options.largeTimestep = 1.0 / 60.0;
  options.modalCheck = true;
  options.frameRate = 30.0;
  return options;
}

/// The same positions and elements with every element of one material.
inline TetMesh withOneMaterial(const TetMesh& mesh, const Material& material) {
  return TetMesh(mesh.restPositions(), mesh.elements(), {material},
                 std::vector<int>(static_cast<std::size_t>(mesh.numElements()), 0));
}

}  // namespace asyncfem::test
