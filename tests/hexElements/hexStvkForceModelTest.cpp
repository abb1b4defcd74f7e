// SPDX-License-Identifier: BSD-3-Clause
// StVK assembled over a hexahedral mesh (HexStvkForceModel): forces against central
// differences of the energy, the tangent against central differences of the forces, the
// fixed pattern, and the rest tangent against the assembled linear stiffness.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/hexElements/hexStvkForceModel.hpp>
#include <cmath>

#include "hexBar.hpp"

namespace asyncfem {
namespace {

/// A large deformation of the bar: a rotation, a stretch and a vertex-wise perturbation.
Eigen::VectorXd largeDisplacement(const TetMesh& mesh) {
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, -2, 1).normalized()).toRotationMatrix();
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    const Eigen::Vector3d wobble = 0.02 * Eigen::Vector3d(std::sin(3.0 * v), std::cos(5.0 * v), std::sin(7.0 * v));
    u.segment<3>(3 * v) = rotation * Eigen::Vector3d(1.1 * x.x(), 0.95 * x.y(), x.z()) + wobble - x;
  }
  return u;
}

TEST(HexStvkForceModel, AssembledForcesAndTangentAreTheEnergyDerivatives) {
  const TetMesh mesh = test::hexBar(1);
  HexStvkForceModel model(mesh);
  const Eigen::VectorXd u = largeDisplacement(mesh);
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> tangent = model.createStiffnessMatrix();
  const Eigen::Index pattern = tangent.nonZeros();
  model.forcesAndTangent(u, forces, tangent);
  EXPECT_EQ(tangent.nonZeros(), pattern);  // the pattern stays what createStiffnessMatrix() gave
  // Central differences with step 1e-7 (displacements of order 0.1, forces of order 1e4):
  // truncation ~ step^2, cancellation ~ 1e-16 |E| / step ~ 1e-9 relative; 1e-6 of the
  // largest entry separates round-off from a wrong or missing assembled block.
  const double step = 1e-7;
  Eigen::VectorXd numericForces(mesh.numDofs());
  Eigen::MatrixXd numericTangent(mesh.numDofs(), mesh.numDofs());
  for (int k = 0; k < mesh.numDofs(); ++k) {
    Eigen::VectorXd plus = u, minus = u;
    plus[k] += step;
    minus[k] -= step;
    numericForces[k] = (model.elasticEnergy(plus) - model.elasticEnergy(minus)) / (2.0 * step);
    Eigen::VectorXd forcesPlus, forcesMinus;
    model.internalForces(plus, forcesPlus);
    model.internalForces(minus, forcesMinus);
    numericTangent.col(k) = (forcesPlus - forcesMinus) / (2.0 * step);
  }
  EXPECT_LE((forces - numericForces).cwiseAbs().maxCoeff(), 1e-6 * forces.cwiseAbs().maxCoeff());
  const Eigen::MatrixXd dense(tangent);
  EXPECT_LE((dense - numericTangent).cwiseAbs().maxCoeff(), 1e-6 * dense.cwiseAbs().maxCoeff());
}

TEST(HexStvkForceModel, AtRestTheTangentIsTheLinearStiffness) {
  const TetMesh mesh = test::hexBar(1);
  HexStvkForceModel model(mesh);
  Eigen::SparseMatrix<double> tangent = model.createStiffnessMatrix();
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.numDofs());
  model.tangentStiffness(zero, tangent);
  const Eigen::MatrixXd linear(hexLinearStiffnessMatrix(mesh));
  // The same 2 x 2 x 2 rule and B^T C B at F = I: equal to the rounding of |K|.
  EXPECT_LE((Eigen::MatrixXd(tangent) - linear).cwiseAbs().maxCoeff(), 1e-12 * linear.cwiseAbs().maxCoeff());
  Eigen::VectorXd forces;
  model.internalForces(zero, forces);
  // E = 0 up to the rounding of F^T F - I (1e-16): stresses of order E * 1e-16 = 1e-10.
  EXPECT_LE(forces.cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LE(std::abs(model.elasticEnergy(zero)), 1e-15);
  EXPECT_THROW(model.internalForces(Eigen::VectorXd::Zero(3), forces), Error);
}

}  // namespace
}  // namespace asyncfem
