// SPDX-License-Identifier: BSD-3-Clause
// K, M and a dense reference eigendecomposition of small meshes for the modal tests.
#pragma once

#include <Eigen/Eigenvalues>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <utility>
#include <vector>

namespace asyncfem::testing {

struct ModalSystem {
  Eigen::SparseMatrix<double> stiffness, mass;  // full 3n x 3n
  FreeDofs freeDofs;
};

/// A box mesh of the given size (m) and cells with the default material.
inline TetMesh boxMesh(const Eigen::Vector3d& size, const Eigen::Vector3i& cells) {
  BoxMeshSpec spec;
  spec.size = size;
  spec.cells = cells;
  return makeBoxMesh(spec);
}

inline ModalSystem modalSystem(const TetMesh& mesh, const std::vector<int>& fixedVertices, MassType massType) {
  VibrationMatrices matrices = vibrationMatrices(mesh, massType);
  return {std::move(matrices.stiffness), std::move(matrices.mass),
          FreeDofs::fromFixedVertices(mesh.numVertices(), fixedVertices)};
}

/// The count lowest modes of the system with the default options.
inline ModalResult lowestModesOf(const ModalSystem& system, int count) {
  ModalOptions options;
  options.count = count;
  return lowestModes(system.stiffness, system.mass, system.freeDofs, options);
}

/// Every mode of the system from Eigen's dense GeneralizedSelfAdjointEigenSolver, as a
/// ModalResult (full vectors, M-orthonormal, ascending).
inline ModalResult denseModes(const ModalSystem& system) {
  const std::vector<int>& free = system.freeDofs.freeToFull();
  const Eigen::MatrixXd stiffness =
      Eigen::MatrixXd(SubmatrixExtractor(system.stiffness, free, free).extract(system.stiffness));
  const Eigen::MatrixXd mass = Eigen::MatrixXd(SubmatrixExtractor(system.mass, free, free).extract(system.mass));
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eigen(stiffness, mass);
  ModalResult result;
  result.eigenvalues = eigen.eigenvalues();
  result.frequencies = result.eigenvalues.cwiseMax(0.0).cwiseSqrt();
  result.modes.setZero(system.freeDofs.numDofs(), stiffness.cols());
  for (Eigen::Index j = 0; j < stiffness.cols(); ++j)
    result.modes.col(j) = system.freeDofs.expand(eigen.eigenvectors().col(j));
  return result;
}

}  // namespace asyncfem::testing
