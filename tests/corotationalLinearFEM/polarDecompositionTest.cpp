// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <cmath>
#include <random>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

// Every tolerance below is relative to quantities of size 1 (F, R, S are dimensionless
// and of order 1): a Jacobi SVD of a 3x3 matrix is backward stable, so residuals are a
// few ulps; 1e-12 leaves room for the products that follow it.
void expectValidDecomposition(const Eigen::Matrix3d& f) {
  const PolarDecomposition polar = polarDecomposition(f);
  const Eigen::Matrix3d& r = polar.rotation;
  EXPECT_TRUE(r.allFinite());
  EXPECT_NEAR(r.determinant(), 1.0, 1e-12);
  EXPECT_LE((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_LE((r * polar.stretch - f).norm(), 1e-12 * std::max(1.0, f.norm()));
  EXPECT_EQ(polar.stretch, polar.stretch.transpose());
  EXPECT_NEAR(polar.rightSingularVectors.determinant(), 1.0, 1e-12);
  // The sign of the last singular value carries the orientation.
  const double det = f.determinant();
  if (std::abs(det) > 1e-9) {
    EXPECT_EQ(polar.singularValues[2] < 0.0, det < 0.0);
  }
}

TEST(PolarDecomposition, RandomMatricesOfBothOrientations) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  int inverted = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix3d f;
    for (int k = 0; k < 9; ++k) f.data()[k] = entry(random);
    inverted += f.determinant() < 0.0 ? 1 : 0;
    expectValidDecomposition(f);
  }
  EXPECT_GT(inverted, 50);  // the sample really covers inverted matrices
}

TEST(PolarDecomposition, PureRotationsAreReturnedExactlyUpToRounding) {
  std::mt19937 random(11);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d q = test::randomRotation(random);
    EXPECT_LE((polarDecomposition(q).rotation - q).norm(), 1e-13);
  }
  // 180 degrees: R is not near the identity, and F's singular values are all equal.
  const Eigen::Matrix3d halfTurn = Eigen::AngleAxisd(M_PI, Eigen::Vector3d(1, 1, 1).normalized()).toRotationMatrix();
  EXPECT_LE((polarDecomposition(halfTurn).rotation - halfTurn).norm(), 1e-13);
}

TEST(PolarDecomposition, FlatAndCollapsedMatricesGiveRotations) {
  std::mt19937 random(3);
  const Eigen::Matrix3d q = test::randomRotation(random);
  expectValidDecomposition(q * Eigen::Vector3d(2.0, 1.0, 0.0).asDiagonal());    // flat: rank 2
  expectValidDecomposition(q * Eigen::Vector3d(1.5, 0.0, 0.0).asDiagonal());    // a line: rank 1
  expectValidDecomposition(Eigen::Matrix3d::Zero());                            // collapsed to a point
  expectValidDecomposition(q * Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal());   // reflected
  expectValidDecomposition(q * Eigen::Vector3d(1.0, 0.5, -1e-9).asDiagonal());  // barely inverted
}

// dR against central differences of R(F + t dF). Step 1e-6 on entries of size 1: the
// truncation error is about t^2 |R'''| ~ 1e-12 and rounding eps / t ~ 1e-10, so 1e-7 of
// |dR| (which is of size 1 here) separates a correct formula from any wrong term.
void expectDifferentialMatchesFiniteDifferences(const Eigen::Matrix3d& f, std::mt19937& random) {
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  const PolarDecomposition polar = polarDecomposition(f);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::Matrix3d df;
    for (int k = 0; k < 9; ++k) df.data()[k] = entry(random);
    const double step = 1e-6;
    const Eigen::Matrix3d finiteDifference =
        (polarDecomposition(f + step * df).rotation - polarDecomposition(f - step * df).rotation) / (2.0 * step);
    const Eigen::Matrix3d analytic = rotationDifferential(polar, df);
    EXPECT_LE((analytic - finiteDifference).norm(), 1e-7 * std::max(1.0, finiteDifference.norm())) << "F =\n"
                                                                                                   << f << "\ndF =\n"
                                                                                                   << df;
    // dR = R W with W skew: R^T dR must be skew.
    const Eigen::Matrix3d w = polar.rotation.transpose() * analytic;
    EXPECT_LE((w + w.transpose()).norm(), 1e-12 * std::max(1.0, w.norm()));
  }
}

TEST(PolarDecomposition, RotationDifferentialMatchesFiniteDifferences) {
  std::mt19937 random(5);
  const Eigen::Matrix3d q = test::randomRotation(random);
  const Eigen::Matrix3d p = test::randomRotation(random);
  // Stretched and rotated, well separated singular values.
  expectDifferentialMatchesFiniteDifferences(q * Eigen::Vector3d(1.3, 0.9, 0.6).asDiagonal() * p, random);
  // Near the identity (all singular values close: the SVD basis is ill-defined there,
  // but R and dR are not).
  expectDifferentialMatchesFiniteDifferences(q * (Eigen::Matrix3d::Identity() + 1e-3 * p), random);
  // Inverted, away from sigma_1 + sigma_2 = 0.
  expectDifferentialMatchesFiniteDifferences(q * Eigen::Vector3d(1.2, 0.8, -0.3).asDiagonal() * p, random);
}

TEST(PolarDecomposition, DifferentialStaysFiniteWhereRIsNotDifferentiable) {
  // Two zero singular values: sigma_1 + sigma_2 = 0 is clamped.
  const Eigen::Matrix3d line = Eigen::Vector3d(1.0, 0.0, 0.0).asDiagonal();
  EXPECT_TRUE(rotationDifferential(polarDecomposition(line), Eigen::Matrix3d::Ones()).allFinite());
  const Eigen::Matrix3d reflection = Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal();
  EXPECT_TRUE(rotationDifferential(polarDecomposition(reflection), Eigen::Matrix3d::Ones()).allFinite());
}

}  // namespace
}  // namespace asyncfem
