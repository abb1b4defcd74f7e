// SPDX-License-Identifier: BSD-3-Clause
// VertexRotations, the rotations behind the turned lagged factor (Eqs. T1 and T2 of
// docs/asynchronous-integrator.md), against rigid motions of a deformed bar, where every
// vertex's rotation is the motion's. Tolerance 1e-12: each rotation is the polar rotation
// of a mean of products of 3 x 3 matrices of order one, equal to R to a few ulps.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/asyncIntegrator/detail/vertexRotations.hpp>
#include <numeric>
#include <random>
#include <vector>

#include "../common/gaussianMatrix.hpp"
#include "../common/testProblems.hpp"

namespace asyncfem {
namespace {

constexpr double kTolerance = 1e-12;

struct TurnedBar {
  std::shared_ptr<const TetMesh> mesh = test::rubberBarMesh(Eigen::Vector3i(4, 2, 1));
  Eigen::VectorXd reference, turned;  // displacements: deformed, then that turned rigidly
  Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  TurnedBar() {
    std::mt19937 random(5);
    std::uniform_real_distribution<double> draw(-0.02, 0.02);
    reference.resize(mesh->numDofs());
    for (Eigen::Index k = 0; k < reference.size(); ++k) reference[k] = draw(random);
    turned.resize(mesh->numDofs());
    const Eigen::Vector3d shift(0.3, -0.1, 0.2);
    for (int v = 0; v < mesh->numVertices(); ++v) {
      const Eigen::Vector3d x = mesh->restPosition(v) + reference.segment<3>(3 * v);
      turned.segment<3>(3 * v) = rotation * x + shift - mesh->restPosition(v);
    }
  }
  std::vector<int> allDofs() const {
    std::vector<int> dofs(static_cast<std::size_t>(mesh->numDofs()));
    std::iota(dofs.begin(), dofs.end(), 0);
    return dofs;
  }
};

// From a deformed reference turned rigidly by R: R at every vertex, R^T undoes it, and a
// block B on every DOF becomes blockdiag(R) B blockdiag(R)^T.
TEST(VertexRotations, ARigidTurnOfADeformedReferenceIsEveryVertexsRotation) {
  const TurnedBar bar;
  detail::VertexRotations rotations;
  rotations.setReference(*bar.mesh, bar.reference);
  rotations.update(*bar.mesh, bar.turned);
  EXPECT_NEAR(rotations.largestAngle(), 0.7, kTolerance);
  const std::vector<int> dofs = bar.allDofs();
  const Eigen::VectorXd x = test::gaussianMatrix(bar.mesh->numDofs(), 1, 1);
  Eigen::VectorXd y = x;
  rotations.rotate(dofs, y, false);
  Eigen::MatrixXd blockRotation = Eigen::MatrixXd::Zero(bar.mesh->numDofs(), bar.mesh->numDofs());
  for (int v = 0; v < bar.mesh->numVertices(); ++v) blockRotation.block<3, 3>(3 * v, 3 * v) = bar.rotation;
  EXPECT_LE((y - blockRotation * x).norm(), kTolerance * x.norm());
  rotations.rotate(dofs, y, true);
  EXPECT_LE((y - x).norm(), kTolerance * x.norm());
  const Eigen::MatrixXd block = test::gaussianMatrix(bar.mesh->numDofs(), bar.mesh->numDofs(), 2);
  Eigen::MatrixXd turnedBlock = block;
  rotations.turnBlock(dofs, turnedBlock);
  const Eigen::MatrixXd expected = blockRotation * block * blockRotation.transpose();
  EXPECT_LE((turnedBlock - expected).norm(), kTolerance * block.norm());
}

// At the reference state every rotation is the identity; a vertex of which a DOF list holds
// only some DOFs (a fixed one) is left as it is, the others are turned.
TEST(VertexRotations, IdentityAtTheReferenceAndPartialVerticesLeftAlone) {
  const TurnedBar bar;
  detail::VertexRotations rotations;
  rotations.setReference(*bar.mesh, bar.reference);
  rotations.update(*bar.mesh, bar.reference);
  EXPECT_LT(rotations.largestAngle(), 1e-6);  // acos near 1: sqrt of a few ulps
  std::vector<int> dofs = bar.allDofs();
  const Eigen::VectorXd x = test::gaussianMatrix(bar.mesh->numDofs(), 1, 3);
  Eigen::VectorXd y = x;
  rotations.rotate(dofs, y, false);
  EXPECT_LE((y - x).norm(), kTolerance * x.norm());

  rotations.update(*bar.mesh, bar.turned);
  dofs.erase(dofs.begin() + 1);  // vertex 0 keeps DOFs 0 and 2 only
  Eigen::VectorXd onDofs(static_cast<Eigen::Index>(dofs.size()));
  for (std::size_t k = 0; k < dofs.size(); ++k) onDofs[static_cast<Eigen::Index>(k)] = x[dofs[k]];
  Eigen::VectorXd turned = onDofs;
  rotations.rotate(dofs, turned, false);
  EXPECT_EQ(turned[0], onDofs[0]);
  EXPECT_EQ(turned[1], onDofs[1]);
  const Eigen::Vector3d vertex1 = bar.rotation * onDofs.segment<3>(2);  // DOFs 3..5
  EXPECT_LE((turned.segment<3>(2) - vertex1).norm(), kTolerance * vertex1.norm());
}

}  // namespace
}  // namespace asyncfem
