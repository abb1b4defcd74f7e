// SPDX-License-Identifier: BSD-3-Clause
#include "detail/interfaceElements.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <string>

#include "detail/elementTangents.hpp"
#include "detail/meshElements.hpp"
#include "detail/sparseBlocks.hpp"

namespace asyncfem::detail {

namespace {

/// The matrix model's K against the mesh's linear FEM stiffness on the columns of the
/// interface DOFs (see findInterfaceElements).
void checkLinearModelMatchesMesh(const TetMesh& mesh, const RegionPartition& partition, const DynamicSystem& system,
                                 const Eigen::SparseMatrix<double>* knownStiffness) {
  Eigen::SparseMatrix<double> evaluated;
  if (knownStiffness == nullptr) {
    evaluated = system.forceModel->createStiffnessMatrix();
    system.forceModel->tangentStiffness(Eigen::VectorXd::Zero(mesh.numDofs()), evaluated);
  }
  const Eigen::SparseMatrix<double>& stiffness = knownStiffness != nullptr ? *knownStiffness : evaluated;
  std::vector<int> columnOf(static_cast<std::size_t>(mesh.numDofs()), -1);
  std::vector<int> columns;
  for (int i = 0; i < partition.numRegions(); ++i)
    for (int dof : partition.interfaceDofs(i)) {
      if (columnOf[static_cast<std::size_t>(dof)] < 0) {
        columnOf[static_cast<std::size_t>(dof)] = static_cast<int>(columns.size());
        columns.push_back(dof);
      }
    }
  if (columns.empty()) return;
  // Sparse 3n x |columns| blocks, so the check costs O(interface elements), not O(n |I|).
  std::vector<Eigen::Triplet<double>> meshEntries, modelEntries;
  const ElementTangents tangents(mesh, *system.forceModel, "async integrator");
  const int size = elementDofs(mesh);
  for (int e = 0; e < mesh.numElements(); ++e) {
    bool touches = false;
    for (int q = 0; q < size && !touches; ++q)
      touches = columnOf[static_cast<std::size_t>(elementDof(mesh, e, q))] >= 0;
    if (!touches) continue;
    const Eigen::MatrixXd ke = tangents.linear(e);
    for (int q = 0; q < size; ++q) {
      const int column = columnOf[static_cast<std::size_t>(elementDof(mesh, e, q))];
      if (column < 0) continue;
      for (int p = 0; p < size; ++p) meshEntries.emplace_back(elementDof(mesh, e, p), column, ke(p, q));
    }
  }
  for (std::size_t k = 0; k < columns.size(); ++k)
    for (SparseMatrix::InnerIterator it(stiffness, columns[k]); it; ++it)
      modelEntries.emplace_back(static_cast<int>(it.row()), static_cast<int>(k), it.value());
  SparseMatrix fromMesh(mesh.numDofs(), static_cast<Eigen::Index>(columns.size()));
  SparseMatrix fromModel(fromMesh.rows(), fromMesh.cols());
  fromMesh.setFromTriplets(meshEntries.begin(), meshEntries.end());
  fromModel.setFromTriplets(modelEntries.begin(), modelEntries.end());
  const SparseMatrix differenceMatrix = fromMesh - fromModel;
  const double scale = std::max(largestMagnitude(fromMesh), 1e-300);
  const double difference = largestMagnitude(differenceMatrix) / scale;
  if (!(difference <= 1e-10)) {
    throw ValidationError(
        "async integrator: the stable coupling needs the stiffness of each interface element; the force model "
        "gives no per-element tangent and its K differs from the mesh's linear FEM stiffness on the interface "
        "columns (relative difference " +
        std::to_string(difference) + "): build it from this mesh, or use the coupling \"paper\"");
  }
}

}  // namespace

bool findInterfaceElements(const TetMesh& mesh, const RegionPartition& partition, const DynamicSystem& system,
                           std::vector<FastRegion>& regions, const Eigen::SparseMatrix<double>* knownStiffness) {
  const std::vector<int>& vertexRegion = partition.vertexRegion();
  std::vector<std::vector<int>> interfaceIndex(regions.size());
  for (int i = 0; i < partition.numRegions(); ++i) {
    std::vector<int>& index = interfaceIndex[static_cast<std::size_t>(i)];
    index.assign(static_cast<std::size_t>(mesh.numDofs()), -1);
    const std::vector<int>& iface = partition.interfaceDofs(i);
    for (std::size_t k = 0; k < iface.size(); ++k) index[static_cast<std::size_t>(iface[k])] = static_cast<int>(k);
  }
  const ElementTangents tangents(mesh, *system.forceModel, "async integrator (stable coupling)",
                                 "use the coupling \"paper\"");
  const bool perElement = tangents.perElement();
  const int size = elementDofs(mesh);
  for (int e = 0; e < mesh.numElements(); ++e) {
    int fast = -1;
    bool touchesLarge = false;
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int region = vertexRegion[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (region >= 0) fast = region;
      if (region < 0) touchesLarge = true;
    }
    if (fast < 0 || !touchesLarge) continue;
    InterfaceElement element;
    element.element = e;
    element.interfaceIndex.resize(static_cast<std::size_t>(size));
    for (int p = 0; p < size; ++p)
      element.interfaceIndex[static_cast<std::size_t>(p)] =
          interfaceIndex[static_cast<std::size_t>(fast)][static_cast<std::size_t>(elementDof(mesh, e, p))];
    if (!perElement) element.tangent = tangents.linear(e);
    regions[static_cast<std::size_t>(fast)].interfaceElements.push_back(element);
  }
  if (perElement) return true;
  checkLinearModelMatchesMesh(mesh, partition, system, knownStiffness);
  return false;
}

}  // namespace asyncfem::detail
