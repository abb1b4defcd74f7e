// SPDX-License-Identifier: BSD-3-Clause
// Linear FEM on hexahedra against the 6-tetrahedra-per-cube split of the same cubes: a
// cantilever under its own weight. They are different elements, so they agree only to
// discretization; the assertions are the bounds that follow from the theory, not numbers
// taken from a run.
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/hexToTets.hpp>
#include <vector>

#include "discretizationAgreement.hpp"
#include "hexBar.hpp"

namespace asyncfem {
namespace {

using test::hexBar;

/// Compliance f . u of the static solve K u = f with f = M g (consistent mass: the exact
/// load functional of gravity restricted to the element space), the x = 0 face fixed.
double compliance(const TetMesh& mesh, const Eigen::SparseMatrix<double>& stiffness,
                  const Eigen::SparseMatrix<double>& mass) {
  std::vector<int> fixed;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).x() == 0.0) fixed.push_back(v);
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), fixed);
  Eigen::VectorXd gravity = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) gravity[3 * v + 1] = -9.81;
  const Eigen::VectorXd load = dofs.restrict(mass * gravity);
  std::vector<Eigen::Triplet<double>> entries;
  for (int c = 0; c < stiffness.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(stiffness, c); it; ++it) {
      const int row = dofs.fullToFree()[static_cast<std::size_t>(it.row())];
      const int col = dofs.fullToFree()[static_cast<std::size_t>(it.col())];
      if (row >= 0 && col >= 0) entries.emplace_back(row, col, it.value());
    }
  Eigen::SparseMatrix<double> reduced(dofs.numFree(), dofs.numFree());
  reduced.setFromTriplets(entries.begin(), entries.end());
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(reduced);
  EXPECT_EQ(solver.info(), Eigen::Success);
  return load.dot(solver.solve(load));
}

double hexCompliance(const TetMesh& hexes) {
  return compliance(hexes, hexLinearStiffnessMatrix(hexes), hexMassMatrix(hexes, MassType::consistent));
}

double tetCompliance(const TetMesh& hexes) {
  const TetMesh tets = hexahedraToTetrahedra(hexes);
  const MatrixAssembler assembler(tets);
  return compliance(tets, linearStiffnessMatrix(tets, assembler), massMatrix(tets, assembler, MassType::consistent));
}

TEST(HexVersusTets, CantileverAgreesOnlyToDiscretization) {
  const TetMesh coarse = hexBar(1);  // 4 x 1 x 1 cubes
  const TetMesh fine = hexBar(2);    // 8 x 2 x 2 cubes: each coarse cube cut into 8
  // Same cubes, same mass: the loads are the same functional.
  test::expectAgreementOnlyToDiscretization(
      {hexCompliance(coarse), hexCompliance(fine), tetCompliance(coarse), tetCompliance(fine)});
}

}  // namespace
}  // namespace asyncfem
