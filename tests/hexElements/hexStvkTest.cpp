// SPDX-License-Identifier: BSD-3-Clause
// StVK on the hexahedron: forces against central differences of the energy, the tangent
// against central differences of the forces, the rest tangent against the linear stiffness.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <asyncfem/hexElements/hexStvk.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <cmath>

#include "hexElementShapes.hpp"

namespace asyncfem {
namespace {

constexpr double kYoung = test::kHexYoung;
constexpr double kPoisson = test::kHexPoisson;
using test::hexRestShape;
HexElementPositions restShape() { return hexRestShape(); }

/// A large deformation: rotation, stretch and a vertex-wise perturbation.
HexElementPositions deformedShape(const HexElementPositions& rest) {
  Eigen::Matrix3d map;
  map << 1.1, -0.3, 0.2,  //
      0.25, 0.9, -0.1,    //
      -0.15, 0.2, 1.2;
  HexElementPositions x = map * rest;
  for (int a = 0; a < 8; ++a) x.col(a) += 0.05 * Eigen::Vector3d(std::sin(a), std::cos(2.0 * a), std::sin(3.0 * a));
  return x;
}

TEST(HexStvk, ForcesAreTheEnergyGradientAndTangentTheForceJacobian) {
  const HexElementPositions rest = restShape();
  const HexElementPositions x = deformedShape(rest);
  const HexStvkElement element = hexStvk(rest, x, kYoung, kPoisson);
  // Central differences with step 1e-6 (positions of order 1): truncation ~ h^2 |third
  // derivative| ~ 1e-12 relative, cancellation ~ 1e-16 |E| / h ~ 1e-10 relative; 1e-6
  // relative to the largest entry leaves a wide margin and still fails for a wrong term.
  const double step = 1e-6;
  HexElementVector numericForce;
  HexElementMatrix numericTangent;
  for (int k = 0; k < 24; ++k) {
    HexElementPositions plus = x, minus = x;
    plus(k % 3, k / 3) += step;
    minus(k % 3, k / 3) -= step;
    const HexStvkElement up = hexStvk(rest, plus, kYoung, kPoisson);
    const HexStvkElement down = hexStvk(rest, minus, kYoung, kPoisson);
    numericForce[k] = (up.energy - down.energy) / (2.0 * step);
    numericTangent.col(k) = (up.force - down.force) / (2.0 * step);
  }
  EXPECT_LE((element.force - numericForce).cwiseAbs().maxCoeff(), 1e-6 * element.force.cwiseAbs().maxCoeff());
  EXPECT_LE((element.tangent - numericTangent).cwiseAbs().maxCoeff(), 1e-6 * element.tangent.cwiseAbs().maxCoeff());
  EXPECT_GT(element.force.norm(), 0.0);
}

TEST(HexStvk, RestStateHasNoForceAndTheLinearStiffness) {
  const HexElementPositions rest = restShape();
  const HexStvkElement element = hexStvk(rest, rest, kYoung, kPoisson);
  const HexElementMatrix linear = hexLinearStiffness(rest, kYoung, kPoisson);
  // E = 0 up to the rounding of F^T F - I (1e-16), so stresses of order 1e6 * 1e-16.
  EXPECT_LE(std::abs(element.energy), 1e-18);
  EXPECT_LE(element.force.cwiseAbs().maxCoeff(), 1e-8);
  // Same 2x2x2 rule, the same B^T C B at F = I: equal to rounding of |K| (1e6).
  EXPECT_LE((element.tangent - linear).cwiseAbs().maxCoeff(), 1e-12 * linear.cwiseAbs().maxCoeff());
  // A rigid rotation leaves energy and force zero (StVK is frame-invariant).
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const HexStvkElement rotated = hexStvk(rest, rotation * rest, kYoung, kPoisson, false);
  EXPECT_LE(std::abs(rotated.energy), 1e-9);
  EXPECT_LE(rotated.force.cwiseAbs().maxCoeff(), 1e-8);
}

}  // namespace
}  // namespace asyncfem
