// SPDX-License-Identifier: BSD-3-Clause
// The isotropic hyperelastic materials on the hexahedron (hexIsotropicHyperelastic): forces
// against central differences of the energy and the tangent against central differences of
// the forces at moderate and large strain, rigid motions, the small-strain limit against
// linear FEM, and an inverted element under the tetrahedra's inversion options.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <asyncfem/hexElements/hexHyperelastic.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../hyperelasticFEM/testHelpers.hpp"
#include "hexElementShapes.hpp"

namespace asyncfem {
namespace {

using test::hexRestShape;

constexpr HyperelasticMaterialKind kKinds[] = {HyperelasticMaterialKind::stvk, HyperelasticMaterialKind::neoHookean,
                                               HyperelasticMaterialKind::mooneyRivlin};

/// The test material: E, nu of hexElementShapes.hpp and Mooney-Rivlin parameters with the
/// same small-strain moduli.
Material material() {
  return Material{"m", 1000.0, test::kHexYoung, test::kHexPoisson,
                  test::matchingMooneyRivlin(test::kHexYoung, test::kHexPoisson)};
}

/// stvk through principal stretches (the isotropic StVK), the other kinds as given.
IsotropicMaterialPoint materialPoint(HyperelasticMaterialKind kind, HyperelasticOptions options = {}) {
  options.stvkFormulation = StVKFormulation::principalStretches;
  return IsotropicMaterialPoint(kind, material(), options);
}

/// A random deformation of strain about `strain`: x = Q (A X + d) + t with A = I + strain R,
/// R uniform in [-1, 1]^(3x3), d a vertex-wise perturbation of amplitude strain / 10.
HexElementPositions randomDeformation(const HexElementPositions& rest, double strain, std::mt19937& random) {
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::Matrix3d map = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 9; ++i) map(i % 3, i / 3) += strain * uniform(random);
  HexElementPositions x = map * rest;
  for (int a = 0; a < 8; ++a)
    x.col(a) += 0.1 * strain * Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
  return test::randomRotation(random) * x + Eigen::Vector3d(0.3, -0.2, 0.1).replicate(1, 8);
}

/// Principal stretches of F at every Gauss point (signed: negative where det F < 0).
std::vector<double> gaussPointStretches(const HexElementPositions& rest, const HexElementPositions& x) {
  const HexGaussPoints points = hexGaussPoints(rest);
  std::vector<double> stretches;
  for (const Eigen::Matrix<double, 3, 8>& gradients : points.gradients) {
    const Eigen::Vector3d s = signedSvd(x * gradients.transpose()).stretches;
    stretches.insert(stretches.end(), s.data(), s.data() + 3);
  }
  return stretches;
}

/// Largest entry of |analytic - numeric| relative to the largest of |analytic|, for the
/// forces (against central differences of the energy) and the tangent (of the forces).
struct DerivativeErrors {
  double force = 0.0;
  double tangent = 0.0;
};
DerivativeErrors derivativeErrors(const HexElementPositions& rest, const HexElementPositions& x,
                                  const IsotropicMaterialPoint& point) {
  const HexGaussPoints points = hexGaussPoints(rest);
  const HexElementEnergy element = hexIsotropicHyperelastic(points, x, point);
  // Step 1e-6 on positions of order 0.5: truncation ~ h^2 (1e-12 relative), cancellation
  // ~ 1e-16 |E| / h, about 1e-10 of the forces and of the tangent here.
  const double step = 1e-6;
  const HexElementVector numericForce = test::centralDifferences(x, step, [&](const HexElementPositions& y) {
                                          return hexIsotropicHyperelastic(points, y, point, false).energy;
                                        }).transpose();
  const HexElementMatrix numericTangent = test::centralDifferences(
      x, step, [&](const HexElementPositions& y) { return hexIsotropicHyperelastic(points, y, point, false).force; });
  return {(element.force - numericForce).cwiseAbs().maxCoeff() / element.force.cwiseAbs().maxCoeff(),
          (element.tangent - numericTangent).cwiseAbs().maxCoeff() / element.tangent.cwiseAbs().maxCoeff()};
}

std::string scientific(double value) {
  std::ostringstream out;
  out << std::scientific << std::setprecision(2) << value;
  return out.str();
}

TEST(HexHyperelastic, ForcesAreTheEnergyGradientAndTangentTheForceJacobian) {
  const HexElementPositions rest = hexRestShape();
  std::mt19937 random(11);
  double worstForce = 0.0;
  double worstTangent = 0.0;
  for (const HyperelasticMaterialKind kind : kKinds) {
    const IsotropicMaterialPoint point = materialPoint(kind);
    for (const double strain : {0.1, 0.4}) {
      for (int sample = 0; sample < 3; ++sample) {
        SCOPED_TRACE(toString(kind) + ", strain " + std::to_string(strain) + ", sample " + std::to_string(sample));
        const HexElementPositions x = randomDeformation(rest, strain, random);
        const std::vector<double> stretches = gaussPointStretches(rest, x);
        ASSERT_GT(*std::min_element(stretches.begin(), stretches.end()), 0.2);  // no point near flat
        const DerivativeErrors errors = derivativeErrors(rest, x, point);
        // 1e-6 of the largest entry: 1e4 times the differences' own error, while a missing
        // or wrong term of dP/dF or of the quadrature is of order 1e-2 to 1.
        EXPECT_LE(errors.force, 1e-6);
        EXPECT_LE(errors.tangent, 1e-6);
        worstForce = std::max(worstForce, errors.force);
        worstTangent = std::max(worstTangent, errors.tangent);
      }
    }
  }
  RecordProperty("worstForceError", scientific(worstForce));
  RecordProperty("worstTangentError", scientific(worstTangent));
}

TEST(HexHyperelastic, RigidMotionsGiveNoEnergyAndNoForce) {
  const HexElementPositions rest = hexRestShape();
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(1.1, Eigen::Vector3d(1.0, 2.0, -0.5).normalized()).matrix();
  const HexElementPositions moved = rotation * rest + Eigen::Vector3d(0.3, -1.0, 2.0).replicate(1, 8);
  HyperelasticOptions invertible;
  invertible.inversionThreshold = 0.2;
  invertible.enforceSPD = true;  // through the SVD, as inverted elements are
  for (const HyperelasticMaterialKind kind : kKinds) {
    for (const HyperelasticOptions& options : {HyperelasticOptions{}, invertible}) {
      SCOPED_TRACE(toString(kind) + (options.enforceSPD ? ", SVD path" : ", invariant path"));
      const HexElementEnergy element = hexIsotropicHyperelastic(rest, moved, materialPoint(kind, options), false);
      // F is a rotation up to rounding (1e-16): W ~ E 1e-16 per unit volume and P ~ E 1e-15.
      // Bounds 1e-12 E V and 1e-12 E L^2 (V = 0.06, L^2 = 0.2); a strain of 1e-4 gives
      // energies and forces above both.
      EXPECT_LE(std::abs(element.energy), 1e-12 * test::kHexYoung * 0.06);
      EXPECT_LE(element.force.cwiseAbs().maxCoeff(), 1e-12 * test::kHexYoung * 0.2);
    }
  }
}

TEST(HexHyperelastic, SmallStrainIsLinearFem) {
  const HexElementPositions rest = hexRestShape();
  const HexElementMatrix linear = hexLinearStiffness(rest, test::kHexYoung, test::kHexPoisson);
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  HexElementVector u;
  for (int k = 0; k < 24; ++k) u[k] = 1e-6 * uniform(random);  // strains about 1e-5
  const HexElementPositions x = rest + Eigen::Map<const HexElementPositions>(u.data());
  for (const HyperelasticMaterialKind kind : kKinds) {
    SCOPED_TRACE(toString(kind));
    const IsotropicMaterialPoint point = materialPoint(kind);
    // At rest the same rule integrates the same C (Mooney-Rivlin's parameters give E and
    // nu back): equal to rounding of |K| (1e6).
    const HexElementEnergy atRest = hexIsotropicHyperelastic(rest, rest, point);
    EXPECT_LE((atRest.tangent - linear).cwiseAbs().maxCoeff(), 1e-10 * linear.cwiseAbs().maxCoeff());
    // f(u) = K u + O(|u|^2): relative difference of the order of the strain, 1e-5.
    const HexElementEnergy strained = hexIsotropicHyperelastic(rest, x, point, false);
    const HexElementVector expected = linear * u;
    EXPECT_LE((strained.force - expected).norm(), 1e-3 * expected.norm());
    EXPECT_NEAR(strained.energy, 0.5 * u.dot(expected), 1e-3 * 0.5 * u.dot(expected));
  }
}

/// The test hexahedron with vertex 6 pushed through the element, past its centre towards
/// vertex 0: the Gauss points near vertex 6 invert.
HexElementPositions cornerPushedThrough(const HexElementPositions& rest) {
  HexElementPositions x = rest;
  x.col(6) = rest.col(0) + 0.2 * (rest.col(6) - rest.col(0));
  return x;
}

TEST(HexHyperelastic, InvertedElementHasFiniteForcesAndWithEnforceSpdAPositiveSemidefiniteTangent) {
  const HexElementPositions rest = hexRestShape();
  const HexElementPositions x = cornerPushedThrough(rest);
  const std::vector<double> stretches = gaussPointStretches(rest, x);
  ASSERT_LT(*std::min_element(stretches.begin(), stretches.end()), 0.0);  // some Gauss point inverted
  HyperelasticOptions options;
  options.inversionThreshold = 0.2;
  // Forces and the tangent are exact below the threshold too (the extended energy), away
  // from the threshold itself: no stretch within 1e-3 of it here.
  for (const double s : stretches) ASSERT_GT(std::abs(s - options.inversionThreshold), 1e-3);
  for (const HyperelasticMaterialKind kind : kKinds) {
    SCOPED_TRACE(toString(kind));
    const DerivativeErrors errors = derivativeErrors(rest, x, materialPoint(kind, options));
    EXPECT_LE(errors.force, 1e-6);
    EXPECT_LE(errors.tangent, 1e-6);
    // The exact tangent of the inverted element is indefinite: what enforceSPD changes.
    const Eigen::SelfAdjointEigenSolver<HexElementMatrix> exact(
        hexIsotropicHyperelastic(rest, x, materialPoint(kind, options)).tangent);
    EXPECT_LT(exact.eigenvalues().minCoeff(), -1e-6 * exact.eigenvalues().maxCoeff());

    HyperelasticOptions spd = options;
    spd.enforceSPD = true;
    const HexElementEnergy element = hexIsotropicHyperelastic(rest, x, materialPoint(kind, spd));
    EXPECT_TRUE(std::isfinite(element.energy));
    EXPECT_TRUE(element.force.allFinite());
    ASSERT_TRUE(element.tangent.allFinite());
    const Eigen::SelfAdjointEigenSolver<HexElementMatrix> eigen(element.tangent);
    // A sum of G^T A G with every A clamped to positive semi-definite: negative
    // eigenvalues only from rounding, 1e-12 of the largest.
    EXPECT_GE(eigen.eigenvalues().minCoeff(), -1e-12 * eigen.eigenvalues().maxCoeff());
    // Internal forces resist the push: moving vertex 6 further in costs energy.
    EXPECT_GT(element.force.segment<3>(18).dot(x.col(6) - rest.col(6)), 0.0);
  }
}

}  // namespace
}  // namespace asyncfem
