// SPDX-License-Identifier: BSD-3-Clause
// ElementKernel::batched (four elements per SIMD batch) against ElementKernel::scalar.
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

struct Evaluation {
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> tangent;
  double energy = 0.0;
  std::vector<Eigen::Matrix3d> rotations;
  RotationStats stats;
};

Evaluation evaluate(const TetMesh& mesh, TangentKind kind, ElementKernel kernel, const Eigen::VectorXd& u) {
  CorotationalLinearFEM model(mesh, kind);
  model.setElementKernel(kernel);
  Evaluation result;
  result.tangent = model.createStiffnessMatrix();
  model.forcesAndTangent(u, result.forces, result.tangent);
  result.energy = model.energyOfLastEvaluation();
  result.rotations = model.rotations();
  result.stats = model.rotationStats();
  return result;
}

int invertedElements(const TetMesh& mesh, const Eigen::VectorXd& u) {
  int inverted = 0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    Eigen::Matrix<double, 3, 4> x = mesh.elementRestPositions(e);
    for (int a = 0; a < 4; ++a) x.col(a) += u.segment<3>(3 * mesh.element(e)[a]);
    inverted += (x.col(1) - x.col(0)).cross(x.col(2) - x.col(0)).dot(x.col(3) - x.col(0)) < 0.0 ? 1 : 0;
  }
  return inverted;
}

// Both kernels run the same arithmetic per element (the same Newton iteration, start and
// stopping rule); only the rounding of the 3x3 products and of Rodrigues' formula differs
// in order, a few ulps of each per-element quantity, and the assembly sums the same
// element terms in the same order. 1e-12 of the largest entry leaves a margin of about
// 1000 over that rounding (the differences measured are printed).
constexpr double kRoundingTolerance = 1e-12;

void expectKernelsAgree(const TetMesh& mesh, const Eigen::VectorXd& u, const std::string& label) {
  for (const TangentKind kind : {TangentKind::simple, TangentKind::exact}) {
    const Evaluation batched = evaluate(mesh, kind, ElementKernel::batched, u);
    const Evaluation scalar = evaluate(mesh, kind, ElementKernel::scalar, u);
    const double forceDifference = test::relativeEntryDifference(batched.forces, scalar.forces);
    const double tangentDifference = test::relativeEntryDifference(batched.tangent, scalar.tangent);
    double rotationDifference = 0.0;
    for (std::size_t e = 0; e < scalar.rotations.size(); ++e)
      rotationDifference =
          std::max(rotationDifference, (batched.rotations[e] - scalar.rotations[e]).cwiseAbs().maxCoeff());
    const std::string what = label + (kind == TangentKind::simple ? ", simple tangent" : ", exact tangent");
    std::printf("[ measured ] %s: forces %.2e, tangent %.2e, rotations %.2e of the largest entry\n", what.c_str(),
                forceDifference, tangentDifference, rotationDifference);
    EXPECT_LE(forceDifference, kRoundingTolerance) << what;
    EXPECT_LE(tangentDifference, kRoundingTolerance) << what;
    EXPECT_LE(rotationDifference, kRoundingTolerance) << what;  // rotations have entries up to 1
    EXPECT_NEAR(batched.energy, scalar.energy, kRoundingTolerance * std::abs(scalar.energy)) << what;
    EXPECT_EQ(batched.stats.decompositionFallbacks, scalar.stats.decompositionFallbacks) << what;
  }
}

TEST(CorotationalBatchedKernel, EqualsScalarKernelOnRandomDeformation) {
  const int cells = 3;  // 162 tets: 40 batches of four and two elements on the scalar path
  const TetMesh mesh = test::smallBox(cells);
  ASSERT_NE(mesh.numElements() % 4, 0);
  std::mt19937 random(21);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d(0.3, 0, 0),
                                                       0.1 * test::cellSize(cells), random);
  expectKernelsAgree(mesh, u, "random 10% strain");
}

TEST(CorotationalBatchedKernel, EqualsScalarKernelUnderLargeRotations) {
  const int cells = 3;
  const TetMesh mesh = test::smallBox(cells);
  std::mt19937 random(22);
  for (const double angle : {0.5, 2.0, 3.1}) {  // radians about a random axis, beyond a half turn
    const Eigen::Vector3d axis = test::randomRotation(random).col(0);
    const Eigen::Matrix3d rotation = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    const Eigen::VectorXd u =
        test::deformedDisplacement(mesh, rotation, Eigen::Vector3d::Zero(), 0.05 * test::cellSize(cells), random);
    expectKernelsAgree(mesh, u, "rotation " + std::to_string(angle) + " rad");
  }
}

TEST(CorotationalBatchedKernel, EqualsScalarKernelWithInvertedElements) {
  // Displacements of half and 0.8 of a cell invert elements; their rotations leave the
  // Newton iteration for the SVD (the reflection fix), lane by lane.
  const int cells = 3;
  const TetMesh mesh = test::smallBox(cells);
  std::mt19937 random(23);
  for (const double amplitude : {0.5, 0.8}) {
    const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d::Zero(),
                                                         amplitude * test::cellSize(cells), random);
    ASSERT_GT(invertedElements(mesh, u), 0);
    const Evaluation batched = evaluate(mesh, TangentKind::simple, ElementKernel::batched, u);
    EXPECT_GT(batched.stats.decompositionFallbacks, 0) << "amplitude " << amplitude;
    for (const Eigen::Matrix3d& r : batched.rotations) {
      // Proper rotations from the SVD fallback as from Newton: to rounding.
      EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
    }
    expectKernelsAgree(mesh, u, "amplitude " + std::to_string(amplitude) + " cell");
  }
}

TEST(CorotationalBatchedKernel, NonFiniteDisplacementGivesNonFiniteResultsOfItsElements) {
  const TetMesh mesh = test::smallBox(2);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.numDofs());
  u[0] = std::numeric_limits<double>::quiet_NaN();  // vertex 0
  const Evaluation batched = evaluate(mesh, TangentKind::simple, ElementKernel::batched, u);
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i vertices = mesh.element(e);
    const bool touchesVertex0 = (vertices.array() == 0).any();
    EXPECT_EQ(batched.rotations[static_cast<std::size_t>(e)].allFinite(), !touchesVertex0) << "element " << e;
  }
  EXPECT_FALSE(batched.forces.allFinite());
}

TEST(CorotationalBatchedKernel, WarmStartTakesTheScalarKernel) {
  // The batched kernel starts from the deformation only; with warm starts the results
  // must be those of the scalar kernel bit for bit.
  const TetMesh mesh = test::smallBox(2);
  std::mt19937 random(24);
  const Eigen::VectorXd u = test::deformedDisplacement(mesh, test::randomRotation(random), Eigen::Vector3d::Zero(),
                                                       0.1 * test::cellSize(2), random);
  std::vector<Eigen::VectorXd> f(2);
  for (const ElementKernel kernel : {ElementKernel::batched, ElementKernel::scalar}) {
    CorotationalLinearFEM model(mesh);
    model.setElementKernel(kernel);
    model.setRotationStart(RotationStart::previousEvaluation);
    model.internalForces(u, f[kernel == ElementKernel::batched ? 0 : 1]);
    const Eigen::VectorXd v = 1.1 * u;
    model.internalForces(v, f[kernel == ElementKernel::batched ? 0 : 1]);
  }
  EXPECT_EQ((f[0] - f[1]).cwiseAbs().maxCoeff(), 0.0);
}

}  // namespace
}  // namespace asyncfem
