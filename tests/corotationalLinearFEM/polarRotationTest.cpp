// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "testHelpers.hpp"

namespace asyncfem {
namespace {

// F, R and the operators are dimensionless and of order 1. Newton stops when its step is
// below 1e-9 rad, so the remaining error is O(1e-18) times the conditioning of R (at most
// 1 / kRelativePairSumMargin = 1e3 where Newton is used): 1e-12 bounds it with margin, as
// it bounds the rounding of the SVD it is compared with.
constexpr double kTolerance = 1e-12;

void expectSameAsDecomposition(const Eigen::Matrix3d& f, const Eigen::Matrix3d* warmStart = nullptr) {
  const PolarDecomposition reference = polarDecomposition(f);
  const PolarRotation result = polarRotation(f, warmStart, true);
  EXPECT_TRUE(result.rotation.allFinite());
  EXPECT_NEAR(result.rotation.determinant(), 1.0, kTolerance);
  EXPECT_LE((result.rotation.transpose() * result.rotation - Eigen::Matrix3d::Identity()).norm(), kTolerance);
  EXPECT_LE((result.rotation - reference.rotation).norm(), kTolerance) << "F =\n" << f;
  const Eigen::Matrix3d referenceOperator = rotationDifferentialOperator(reference);
  EXPECT_LE((result.differentialOperator - referenceOperator).norm(),
            kTolerance * std::max(1.0, referenceOperator.norm()))
      << "F =\n"
      << f;
}

TEST(PolarRotation, EqualsTheDecompositionForRandomMatricesOfBothOrientations) {
  std::mt19937 random(17);
  std::uniform_real_distribution<double> entry(-1.0, 1.0);
  int inverted = 0;
  int newton = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Eigen::Matrix3d f;
    for (int k = 0; k < 9; ++k) f.data()[k] = entry(random);
    inverted += f.determinant() < 0.0 ? 1 : 0;
    expectSameAsDecomposition(f);
    newton += polarRotation(f).usedDecomposition ? 0 : 1;
  }
  EXPECT_GT(inverted, 100);  // the sample covers inverted matrices
  EXPECT_GT(newton, 250);    // and mostly exercises the Newton path, not the fallback
}

TEST(PolarRotation, StrainedRotationsConvergeFromEveryStart) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> strain(-0.3, 0.3);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Matrix3d q = test::randomRotation(random);
    Eigen::Matrix3d stretch = Eigen::Matrix3d::Identity();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) stretch(i, j) += strain(random);
    const Eigen::Matrix3d f = q * stretch;
    const PolarRotation cold = polarRotation(f);
    EXPECT_FALSE(cold.usedDecomposition) << "F =\n" << f;
    expectSameAsDecomposition(f);
    // Warm start from a nearby rotation (one timestep of motion): a few steps only.
    const Eigen::Matrix3d nearby = polarDecomposition(f).rotation * Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY());
    const PolarRotation warm = polarRotation(f, &nearby);
    EXPECT_LE(warm.newtonSteps, 3);
    expectSameAsDecomposition(f, &nearby);
  }
}

TEST(PolarRotation, IdentityIsReturnedExactlyAndRotationsToRounding) {
  const PolarRotation rest = polarRotation(Eigen::Matrix3d::Identity());
  EXPECT_EQ(rest.rotation, Eigen::Matrix3d::Identity());
  EXPECT_EQ(rest.newtonSteps, 0);
  std::mt19937 random(23);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d q = test::randomRotation(random);
    EXPECT_LE((polarRotation(q).rotation - q).norm(), kTolerance);
  }
  const Eigen::Matrix3d halfTurn = Eigen::AngleAxisd(M_PI, Eigen::Vector3d(1, 1, 1).normalized()).toRotationMatrix();
  EXPECT_LE((polarRotation(halfTurn).rotation - halfTurn).norm(), kTolerance);
}

TEST(PolarRotation, DegenerateAndInvertedMatricesFallBackToProperRotations) {
  std::mt19937 random(29);
  const Eigen::Matrix3d q = test::randomRotation(random);
  const Eigen::Matrix3d p = test::randomRotation(random);
  // Flat, collapsed to a line, to a point, inverted with sigma_1 = sigma_2 (R not
  // unique), a reflection: every one gives a finite proper rotation, equal to the SVD's.
  const Eigen::Matrix3d cases[] = {
      q * Eigen::Vector3d(2.0, 1.0, 0.0).asDiagonal() * p,
      q * Eigen::Vector3d(1.0, 0.0, 0.0).asDiagonal() * p,
      Eigen::Matrix3d::Zero(),
      q * Eigen::Vector3d(1.0, 0.5, -0.5).asDiagonal() * p,
      q * Eigen::Vector3d(1.0, 1.0, -1.0).asDiagonal() * p,
      q * Eigen::Vector3d(1.0, 0.8, -0.1).asDiagonal() * p,
  };
  for (const Eigen::Matrix3d& f : cases) {
    const PolarRotation result = polarRotation(f, nullptr, true);
    EXPECT_TRUE(result.rotation.allFinite());
    EXPECT_TRUE(result.differentialOperator.allFinite());
    EXPECT_NEAR(result.rotation.determinant(), 1.0, kTolerance);
    EXPECT_LE((result.rotation - polarDecomposition(f).rotation).norm(), kTolerance) << "F =\n" << f;
  }
  // A warm start on the wrong side of an inversion must not lead Newton to a reflection
  // or another critical point: the result is still the SVD's rotation.
  const Eigen::Matrix3d inverted = q * Eigen::Vector3d(1.0, 0.8, -0.1).asDiagonal() * p;
  const Eigen::Matrix3d wrongSide = q * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()) * p;
  EXPECT_LE((polarRotation(inverted, &wrongSide).rotation - polarDecomposition(inverted).rotation).norm(), kTolerance);
}

TEST(PolarRotation, NonFiniteInputGivesNonFiniteOutput) {
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  f(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(polarRotation(f).rotation.allFinite());
}

}  // namespace
}  // namespace asyncfem
