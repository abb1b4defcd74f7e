// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>
#include <cmath>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

using test::ModelCase;

double relativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const double scale = std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff());
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

// A deformation gradient with principal stretches s (the last one may be negative),
// rotated by two fixed rotations so that no stretch is aligned with the axes.
Eigen::Matrix3d withStretches(const Eigen::Vector3d& s) {
  std::mt19937 random(23);
  const Eigen::Matrix3d left = test::randomRotation(random);
  const Eigen::Matrix3d right = test::randomRotation(random);
  return left * s.asDiagonal() * right.transpose();
}

struct Deformation {
  std::string label;
  Eigen::Vector3d stretches;
};

// Nearly flat, inverted, and inverted with two stretches below a 0.2 threshold.
std::vector<Deformation> severeDeformations() {
  return {{"nearly flat", {1.1, 0.95, 0.03}},
          {"inverted", {1.05, 0.9, -0.3}},
          {"inverted, two stretches below 0.2", {1.2, 0.1, -0.5}}};
}

TEST(HyperelasticInversion, SignedSvdKeepsRotationsAndPutsTheSignOnTheSmallestStretch) {
  for (const Deformation& d : severeDeformations()) {
    SCOPED_TRACE(d.label);
    const Eigen::Matrix3d f = withStretches(d.stretches);
    const SignedSvd svd = signedSvd(f);
    EXPECT_NEAR(svd.u.determinant(), 1.0, 1e-12);
    EXPECT_NEAR(svd.v.determinant(), 1.0, 1e-12);
    EXPECT_LE((svd.u * svd.stretches.asDiagonal() * svd.v.transpose() - f).cwiseAbs().maxCoeff(), 1e-12);
    // Same stretches up to order and a sign moved between them: equal magnitudes, equal
    // product (det F), and only the last (smallest) one negative.
    Eigen::Vector3d expected = d.stretches.cwiseAbs();
    std::sort(expected.data(), expected.data() + 3, std::greater<>());
    EXPECT_LE((svd.stretches.cwiseAbs() - expected).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_NEAR(svd.stretches.prod(), d.stretches.prod(), 1e-12);
    EXPECT_GE(svd.stretches[1], 0.0);
    EXPECT_EQ(svd.stretches[2] < 0.0, d.stretches.prod() < 0.0);
  }
}

TEST(HyperelasticInversion, DerivativesHoldForFlatAndInvertedElements) {
  // Same step and tolerance as the smooth case (hyperelasticFEMTest.cpp): the extended
  // energy is smooth away from the threshold itself, and the stretches here are at least
  // 0.1 away from 0.2.
  const TetMesh mesh = test::unitTet();
  for (const ModelCase& c : test::allModelCases()) {
    auto model = makeHyperelasticForceModel(mesh, c.kind, c.options);
    for (const Deformation& d : severeDeformations()) {
      SCOPED_TRACE(c.label + ", " + d.label);
      const Eigen::VectorXd u = test::homogeneousDisplacement(mesh, withStretches(d.stretches));
      const Eigen::VectorXd f = test::forces(*model, u);
      ASSERT_TRUE(f.allFinite());
      ASSERT_TRUE(std::isfinite(model->elasticEnergy(u)));
      EXPECT_LE(relativeDifference(f, test::finiteDifferenceForces(*model, u, 1e-6)), 1e-6);
      EXPECT_LE(relativeDifference(test::tangent(*model, u), test::finiteDifferenceTangent(*model, u, 1e-6)), 1e-6);
    }
  }
}

TEST(HyperelasticInversion, ExtensionIsContinuousAtTheThreshold) {
  // Energy density on both sides of s_3 = c: a jump would show as a difference of order
  // W itself; a continuous first derivative leaves O(t) = 1e-8 of it.
  const TetMesh mesh = test::unitTet();
  HyperelasticOptions options;
  options.inversionThreshold = 0.2;
  for (const auto kind :
       {HyperelasticMaterialKind::stvk, HyperelasticMaterialKind::neoHookean, HyperelasticMaterialKind::mooneyRivlin}) {
    SCOPED_TRACE(toString(kind));
    const IsotropicHyperelasticFEM model(mesh, kind, options);
    const double t = 1e-8;
    const double below = model.energyDensity(0, {1.1, 0.9, 0.2 - t});
    const double above = model.energyDensity(0, {1.1, 0.9, 0.2 + t});
    const double at = model.energyDensity(0, {1.1, 0.9, 0.2});
    const double slope = (above - at) / t;
    EXPECT_NEAR(below, at - slope * t, 1e-6 * std::abs(at));
  }
}

TEST(HyperelasticInversion, VegaClampEvaluatesAtTheClampedStretches) {
  // Vega's mode: below the threshold the stretch is replaced by the threshold, so the
  // energy density (and stress) equal those at the threshold whatever the stretch.
  const TetMesh mesh = test::unitTet();
  HyperelasticOptions options;
  options.inversionThreshold = 0.2;
  options.inversionHandling = InversionHandling::vegaClamp;
  const IsotropicHyperelasticFEM vega(mesh, HyperelasticMaterialKind::neoHookean, options);
  const double atThreshold = vega.energyDensity(0, {1.1, 0.9, 0.2});
  EXPECT_EQ(vega.energyDensity(0, {1.1, 0.9, -0.3}), atThreshold);
  EXPECT_EQ(vega.energyDensity(0, {1.1, 0.9, 0.05}), atThreshold);
  // The consistent extension differs there (it adds g (s - c)).
  options.inversionHandling = InversionHandling::extrapolate;
  const IsotropicHyperelasticFEM extended(mesh, HyperelasticMaterialKind::neoHookean, options);
  EXPECT_GT(std::abs(extended.energyDensity(0, {1.1, 0.9, -0.3}) - atThreshold), 1e-3 * std::abs(atThreshold));
  // Forces stay finite for an inverted element.
  const Eigen::VectorXd u = test::homogeneousDisplacement(mesh, withStretches({1.05, 0.9, -0.3}));
  options.inversionHandling = InversionHandling::vegaClamp;
  IsotropicHyperelasticFEM vegaModel(mesh, HyperelasticMaterialKind::neoHookean, options);
  EXPECT_TRUE(test::forces(vegaModel, u).allFinite());
}

TEST(HyperelasticInversion, PositiveDefiniteTangentOptionClampsEigenvalues) {
  const TetMesh mesh = test::unitTet();
  HyperelasticOptions options;
  options.inversionThreshold = 0.2;
  const Eigen::VectorXd u = test::homogeneousDisplacement(mesh, withStretches({1.2, 0.1, -0.5}));
  IsotropicHyperelasticFEM exact(mesh, HyperelasticMaterialKind::neoHookean, options);
  options.enforceSPD = true;
  IsotropicHyperelasticFEM clamped(mesh, HyperelasticMaterialKind::neoHookean, options);
  const Eigen::VectorXd exactEigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(test::tangent(exact, u)).eigenvalues();
  const Eigen::VectorXd clampedEigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(test::tangent(clamped, u)).eigenvalues();
  const double scale = clampedEigenvalues.cwiseAbs().maxCoeff();
  // The exact tangent of this inverted element is indefinite; the clamped one is PSD up
  // to rounding (1e-12 of its largest eigenvalue).
  EXPECT_LT(exactEigenvalues.minCoeff(), -1e-3 * scale);
  EXPECT_GE(clampedEigenvalues.minCoeff(), -1e-12 * scale);
}

TEST(HyperelasticInversion, FlatElementWithoutHandlingIsReportedNotReturned) {
  const TetMesh mesh = test::unitTet();
  auto model = makeHyperelasticForceModel(mesh, HyperelasticMaterialKind::neoHookean);
  // Exactly flat (z collapsed): J = 0, where log J is -infinity.
  const Eigen::VectorXd u = test::homogeneousDisplacement(mesh, Eigen::Vector3d(1.0, 1.0, 0.0).asDiagonal());
  Eigen::VectorXd f;
  try {
    model->internalForces(u, f);
    FAIL() << "expected a NumericalError";
  } catch (const NumericalError& error) {
    EXPECT_NE(std::string(error.what()).find("element 0"), std::string::npos) << error.what();
  }
}

// Releases a unit tet whose fourth vertex was pushed through the opposite face and
// integrates it with backward Euler (Newton, damped); returns det F at the end. The
// tangent is made positive semi-definite (enforceSPD) because the exact tangent of an
// inverted element is indefinite and the step is solved by Cholesky.
double releaseInvertedTet(HyperelasticOptions options) {
  options.enforceSPD = true;
  const Problem problem(std::make_shared<const TetMesh>(test::unitTet()), {},
                        {.mass = MassType::lumped,
                         .forceModel = ForceModelType::neoHookean,
                         .hyperelastic = options,
                         .rayleighAlpha = 20.0});
  const TetMesh& mesh = problem.mesh();
  IntegratorOptions integratorOptions;
  integratorOptions.maxIterations = 20;
  integratorOptions.tolerance = 1e-10;
  BackwardEuler integrator(problem.dynamicSystem(), 2e-3, integratorOptions);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.numDofs());
  u[11] = -1.6;  // vertex 3 from z = 1 to z = -0.6: det F = -0.6
  integrator.setState(u, Eigen::VectorXd::Zero(mesh.numDofs()));
  for (int step = 0; step < 500; ++step) integrator.step();
  const Eigen::VectorXd& end = integrator.displacement();
  EXPECT_TRUE(end.allFinite());
  Eigen::Matrix3d f;
  for (int a = 1; a < 4; ++a) {
    f.col(a - 1) = (mesh.restPosition(a) + end.segment<3>(3 * a)) - (mesh.restPosition(0) + end.segment<3>(0));
  }
  return f.determinant();
}

TEST(HyperelasticInversion, InvertedTetRecoversWithExtensionAndStaysInvertedWithout) {
  HyperelasticOptions handled;
  handled.inversionThreshold = 0.2;
  // Recovery: the rest shape (det F = 1) within the damping's residual motion.
  EXPECT_NEAR(releaseInvertedTet(handled), 1.0, 0.05);
  // Without inversion handling the neo-Hookean energy depends on |J| only, so the tet
  // settles in the mirror image (det F near -1): the test above would fail without it.
  EXPECT_LT(releaseInvertedTet(HyperelasticOptions{}), -0.5);
}

}  // namespace
}  // namespace asyncfem
