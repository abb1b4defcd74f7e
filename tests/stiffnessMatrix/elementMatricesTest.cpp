// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <random>

namespace asyncfem {
namespace {

// A skewed, positively oriented tetrahedron with edges of order 1.
ElementPositions skewedTet() {
  ElementPositions x;
  x.col(0) << 0.1, -0.2, 0.05;
  x.col(1) << 1.3, 0.1, -0.1;
  x.col(2) << 0.4, 0.9, 0.2;
  x.col(3) << 0.2, 0.3, 1.1;
  return x;
}

double scaledDifference(double a, double b) { return std::abs(a - b) / std::max({1.0, std::abs(a), std::abs(b)}); }

// Linear elastic energy V (mu eps:eps + lambda/2 tr(eps)^2) computed from the deformation
// gradient (Ds Dm^{-1}), independently of the shape-function gradients under test.
double linearElasticEnergy(const ElementPositions& rest, const ElementVector& u, double youngsModulus,
                           double poissonRatio) {
  Eigen::Matrix3d restEdges, displacementEdges;
  for (int k = 0; k < 3; ++k) {
    restEdges.col(k) = rest.col(k + 1) - rest.col(0);
    displacementEdges.col(k) = u.segment<3>(3 * (k + 1)) - u.segment<3>(0);
  }
  const Eigen::Matrix3d displacementGradient = displacementEdges * restEdges.inverse();
  const Eigen::Matrix3d strain = 0.5 * (displacementGradient + displacementGradient.transpose());
  const double volume = std::abs(restEdges.determinant()) / 6.0;
  const double lambda = youngsModulus * poissonRatio / ((1 + poissonRatio) * (1 - 2 * poissonRatio));
  const double mu = youngsModulus / (2 * (1 + poissonRatio));
  return volume * (mu * strain.squaredNorm() + 0.5 * lambda * strain.trace() * strain.trace());
}

TEST(ElementMatrices, LameParametersMatchClosedForm) {
  // E = 2.5, nu = 0.25: lambda = 2.5 * 0.25 / (1.25 * 0.5) = 1, mu = 2.5 / 2.5 = 1.
  const Eigen::Vector2d lame = lameParameters(2.5, 0.25);
  // A few roundings of the two divisions: 4 ulp.
  EXPECT_NEAR(lame[0], 1.0, 4e-16);
  EXPECT_NEAR(lame[1], 1.0, 4e-16);
}

TEST(ElementMatrices, ShapeFunctionGradientsInterpolateLinearFunctions) {
  const ElementPositions x = skewedTet();
  double signedVolume = 0.0;
  const Eigen::Matrix<double, 3, 4> g = shapeFunctionGradients(x, &signedVolume);
  Eigen::Matrix3d edges;
  for (int k = 0; k < 3; ++k) edges.col(k) = x.col(k + 1) - x.col(0);
  // Eigen's determinant and the cross-product form round differently: 1e-14 relative.
  EXPECT_LE(scaledDifference(signedVolume, edges.determinant() / 6.0), 1e-14);
  // N_a(x_b) = delta_ab, so g_a . (x_b - x_0) = delta_ab - delta_a0; and sum_a g_a = 0
  // (partition of unity). Entries are O(1): 1e-14 absolute covers the roundings.
  for (int a = 0; a < 4; ++a) {
    for (int b = 1; b < 4; ++b) {
      const double expected = (a == b ? 1.0 : 0.0) - (a == 0 ? 1.0 : 0.0);
      EXPECT_NEAR(g.col(a).dot(x.col(b) - x.col(0)), expected, 1e-14) << "a=" << a << " b=" << b;
    }
  }
  EXPECT_LE(g.rowwise().sum().norm(), 1e-14 * g.norm());

  ElementPositions swapped = x;
  swapped.col(2).swap(swapped.col(3));
  double swappedVolume = 0.0;
  shapeFunctionGradients(swapped, &swappedVolume);
  EXPECT_LE(scaledDifference(swappedVolume, -signedVolume), 1e-15);
}

TEST(ElementMatrices, StiffnessMatchesFiniteDifferenceOfEnergy) {
  const ElementPositions x = skewedTet();
  const double youngsModulus = 3.0;
  const double poissonRatio = 0.35;
  const ElementMatrix k = linearElementStiffness(x, youngsModulus, poissonRatio);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-0.1, 0.1);
  ElementVector u;
  for (int i = 0; i < 12; ++i) u[i] = uniform(random);
  const ElementVector gradient = k * u;  // dW/du for the quadratic energy W = u^T K u / 2
  // Central differences with step h = 1e-5 (displacements are O(0.1), the element O(1)).
  // W is quadratic, so the truncation error is zero and only the cancellation error
  // eps |W| / h ~ 1e-16 * 1e-2 / 1e-5 = 1e-13 remains, far below the 1e-6 tolerance.
  const double h = 1e-5;
  for (int i = 0; i < 12; ++i) {
    ElementVector plus = u, minus = u;
    plus[i] += h;
    minus[i] -= h;
    const double finiteDifference = (linearElasticEnergy(x, plus, youngsModulus, poissonRatio) -
                                     linearElasticEnergy(x, minus, youngsModulus, poissonRatio)) /
                                    (2 * h);
    EXPECT_LE(std::abs(finiteDifference - gradient[i]), 1e-6 * gradient.norm()) << "dof " << i;
  }
}

TEST(ElementMatrices, StiffnessEqualsVoigtProduct) {
  // Independent construction V B^T C B with 6x12 strain-displacement matrix B (Voigt
  // order xx, yy, zz, yz, xz, xy with engineering shear strains).
  const ElementPositions x = skewedTet();
  const double youngsModulus = 2e6, poissonRatio = 0.3;
  double signedVolume = 0.0;
  const Eigen::Matrix<double, 3, 4> g = shapeFunctionGradients(x, &signedVolume);
  Eigen::Matrix<double, 6, 12> b = Eigen::Matrix<double, 6, 12>::Zero();
  for (int a = 0; a < 4; ++a) {
    b(0, 3 * a) = g(0, a);
    b(1, (3 * a) + 1) = g(1, a);
    b(2, (3 * a) + 2) = g(2, a);
    b(3, (3 * a) + 1) = g(2, a);
    b(3, (3 * a) + 2) = g(1, a);
    b(4, (3 * a) + 0) = g(2, a);
    b(4, (3 * a) + 2) = g(0, a);
    b(5, (3 * a) + 0) = g(1, a);
    b(5, (3 * a) + 1) = g(0, a);
  }
  const Eigen::Vector2d lame = lameParameters(youngsModulus, poissonRatio);
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  c.topLeftCorner<3, 3>().setConstant(lame[0]);
  c.topLeftCorner<3, 3>().diagonal().array() += 2 * lame[1];
  c.bottomRightCorner<3, 3>().diagonal().setConstant(lame[1]);
  const ElementMatrix reference = std::abs(signedVolume) * b.transpose() * c * b;
  const ElementMatrix k = linearElementStiffness(x, youngsModulus, poissonRatio);
  // Same sums in a different order: 1e-14 of the norm.
  EXPECT_LE((k - reference).norm(), 1e-14 * reference.norm());
}

TEST(ElementMatrices, StiffnessIsSymmetricPositiveSemiDefiniteWithRigidNullSpace) {
  const ElementPositions x = skewedTet();
  const ElementMatrix k = linearElementStiffness(x, 1e6, 0.45);
  // Blocks (a, b) and (b, a)^T are the same products in the same order: exact.
  EXPECT_EQ((k - k.transpose()).norm(), 0.0);
  Eigen::SelfAdjointEigenSolver<ElementMatrix> eigen(k);
  const auto values = eigen.eigenvalues();
  // Eigenvalues of a symmetric matrix are accurate to ~eps ||K||; 1e-12 leaves margin.
  for (int i = 0; i < 6; ++i) EXPECT_LE(std::abs(values[i]), 1e-12 * values[11]) << i;
  for (int i = 6; i < 12; ++i) EXPECT_GT(values[i], 1e-6 * values[11]) << i;
  // Rigid modes: translations and rotations about the centroid.
  const Eigen::Vector3d centroid = x.rowwise().mean();
  for (int mode = 0; mode < 6; ++mode) {
    ElementVector r;
    for (int a = 0; a < 4; ++a) {
      r.segment<3>(3 * a) = mode < 3 ? Eigen::Vector3d::Unit(mode)
                                     : Eigen::Vector3d(Eigen::Vector3d::Unit(mode - 3).cross(x.col(a) - centroid));
    }
    // K r cancels terms of size ||K|| ||r||: 1e-13 relative.
    EXPECT_LE((k * r).norm(), 1e-13 * k.norm() * r.norm()) << "mode " << mode;
  }
  // Reversing the vertex order yields the same stiffness (|V| and the same gradients).
  ElementPositions swapped = x;
  swapped.col(2).swap(swapped.col(3));
  ElementMatrix permuted = linearElementStiffness(swapped, 1e6, 0.45);
  Eigen::Matrix<int, 12, 1> order;
  const int vertexOrder[4] = {0, 1, 3, 2};
  for (int a = 0; a < 4; ++a)
    for (int c = 0; c < 3; ++c) order[(3 * a) + c] = (3 * vertexOrder[a]) + c;
  ElementMatrix back;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) back(order[i], order[j]) = permuted(i, j);
  EXPECT_LE((back - k).norm(), 1e-13 * k.norm());
}

TEST(ElementMatrices, MassMatricesSumToElementMass) {
  const double volume = 0.37, density = 2700.0;
  const ElementMatrix consistent = consistentElementMass(volume, density);
  const ElementMatrix lumped = lumpedElementMass(volume, density);
  for (int c = 0; c < 3; ++c) {
    double consistentSum = 0.0, lumpedSum = 0.0;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        consistentSum += consistent((3 * a) + c, (3 * b) + c);
        lumpedSum += lumped((3 * a) + c, (3 * b) + c);
      }
    // Sixteen additions of O(rho V) terms: 1e-14 relative.
    EXPECT_LE(scaledDifference(consistentSum, density * volume), 1e-14);
    EXPECT_LE(scaledDifference(lumpedSum, density * volume), 1e-14);
  }
  EXPECT_DOUBLE_EQ(consistent(0, 0), density * volume / 10.0);
  EXPECT_DOUBLE_EQ(consistent(0, 3), density * volume / 20.0);
  EXPECT_EQ(consistent(0, 1), 0.0);  // coordinates do not couple
  EXPECT_DOUBLE_EQ(lumped(5, 5), density * volume / 4.0);
  EXPECT_EQ((lumped - ElementMatrix(lumped.diagonal().asDiagonal())).norm(), 0.0);
  // Consistent mass is positive definite: eigenvalues rho V / 20 (once 5, thrice 1) per coordinate.
  Eigen::SelfAdjointEigenSolver<ElementMatrix> eigen(consistent);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
}

}  // namespace
}  // namespace asyncfem
