// SPDX-License-Identifier: BSD-3-Clause
// The free-DOF system M + h^2 K of a clamped box, assembled here and solved with every
// sparse solver kind: the matrices this library builds are what the solvers expect
// (full storage, sorted, compressed, symmetric positive definite once DOFs are fixed).
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <random>

#include "testMeshes.hpp"

namespace asyncfem {
namespace {

TEST(FreeSystemSolve, EverySolverKindSolvesClampedBox) {
  const TetMesh mesh = test::mixedMaterialBox(4);
  const MatrixAssembler assembler(mesh);
  const Eigen::SparseMatrix<double> stiffness = linearStiffnessMatrix(mesh, assembler);
  const Eigen::SparseMatrix<double> mass = massMatrix(mesh, assembler, MassType::consistent);
  const double timestep = 1e-2;
  Eigen::SparseMatrix<double> system;
  combine({1.0, timestep * timestep}, {&mass, &stiffness}, system);
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
  const SubmatrixExtractor extractor(system, dofs.freeToFull(), dofs.freeToFull());
  const Eigen::SparseMatrix<double> freeSystem = extractor.extract(system);

  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd rhs(dofs.numFree());
  for (int i = 0; i < rhs.size(); ++i) rhs[i] = uniform(random);

  Eigen::VectorXd first;
  for (SolverKind kind : {SolverKind::cholmod, SolverKind::umfpack, SolverKind::eigenLDLT, SolverKind::eigenLU}) {
    SCOPED_TRACE(toString(kind));
    const std::unique_ptr<SparseSolver> solver = makeSparseSolver(kind);
    solver->compute(freeSystem);
    const Eigen::VectorXd solution = solver->solve(rhs);
    // Direct solvers are backward stable: ||A x - b|| ~ eps ||A|| ||x||, and
    // ||A|| ||x|| <= cond(A) ||b|| with cond(M + h^2 K) about 1e5 here (stiffness contrast
    // 4e4 in the mixed box), so 1e-10 ||b|| leaves a wide margin.
    EXPECT_LE((freeSystem * solution - rhs).norm(), 1e-10 * rhs.norm());
    if (first.size() == 0) {
      first = solution;
    } else {
      // Two backward-stable solutions differ by at most ~cond(A) eps relative.
      EXPECT_LE((solution - first).norm(), 1e-9 * first.norm());
    }
  }
}

}  // namespace
}  // namespace asyncfem
