// SPDX-License-Identifier: BSD-3-Clause
// Builds a beam, assembles and factors M + K, and prints a residual: exit 0 iff it is small.
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cstdio>

int main() {
  using namespace asyncfem;
  const TetMesh mesh = makeBeamMesh(BeamSpec{});
  MatrixAssembler assembler(mesh);
  const Eigen::SparseMatrix<double> K = linearStiffnessMatrix(mesh, assembler);
  const Eigen::SparseMatrix<double> M = massMatrix(mesh, assembler, MassType::consistent);
  const FreeDofs free = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("root"));
  const SubmatrixExtractor extract(K, free.freeToFull(), free.freeToFull());
  Eigen::SparseMatrix<double> A = extract.extract(M);
  A += 1e-4 * extract.extract(K);
  A.makeCompressed();
  auto solver = makeSparseSolver(SolverKind::cholmod);
  solver->compute(A);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows());
  const double residual = (A * solver->solve(b) - b).norm() / b.norm();
  std::printf("consumer: %d tets, residual %.2e\n", mesh.numElements(), residual);
  return residual < 1e-10 ? 0 : 1;
}
