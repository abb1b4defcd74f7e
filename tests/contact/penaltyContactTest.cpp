// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>
#include <cstdlib>

namespace asyncfem {
namespace {

// Two vertices: one above the ground (free), one 0.01 below it.
PenaltyContact twoVertices(PenaltyContactParameters parameters, std::vector<ContactSphere> spheres = {}) {
  Eigen::Matrix3Xd rest(3, 2);
  rest.col(0) = Eigen::Vector3d(0, 1, 0);
  rest.col(1) = Eigen::Vector3d(0, -0.01, 0);
  return PenaltyContact(rest, {ContactPlane{}}, std::move(spheres), parameters);
}

TEST(PenaltyContact, NormalForceIsStiffnessTimesDepth) {
  PenaltyContactParameters p;
  p.stiffness = 1000;
  const PenaltyContact contact = twoVertices(p);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(6);
  contact.addForces(Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(6), f);
  EXPECT_DOUBLE_EQ(f[4], 1000 * 0.01);
  EXPECT_EQ(f.head<3>().norm(), 0.0);
  EXPECT_NEAR(contact.maxPenetration(Eigen::VectorXd::Zero(6)), 0.01, 1e-15);
  EXPECT_EQ(contact.activeContacts(Eigen::VectorXd::Zero(6)), 1);
}

TEST(PenaltyContact, DampingOpposesApproachButNeverPulls) {
  PenaltyContactParameters p;
  p.stiffness = 1000;
  p.damping = 100;
  const PenaltyContact contact = twoVertices(p);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6), f = Eigen::VectorXd::Zero(6);
  v[4] = -1.0;  // moving into the ground: more push
  contact.addForces(Eigen::VectorXd::Zero(6), v, f);
  EXPECT_DOUBLE_EQ(f[4], 10 + 100);
  f.setZero();
  v[4] = 5.0;  // leaving fast: damping would pull, clamped to zero
  contact.addForces(Eigen::VectorXd::Zero(6), v, f);
  EXPECT_EQ(f[4], 0.0);
}

TEST(PenaltyContact, FrictionOpposesSlidingUpToMuTimesNormal) {
  PenaltyContactParameters p;
  p.stiffness = 1000;
  p.friction = 0.5;
  p.frictionViscosity = 1e6;  // sliding regime: the Coulomb bound applies
  const PenaltyContact contact = twoVertices(p);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(6), f = Eigen::VectorXd::Zero(6);
  v[3] = 2.0;
  contact.addForces(Eigen::VectorXd::Zero(6), v, f);
  EXPECT_DOUBLE_EQ(f[3], -0.5 * 10);
  p.frictionViscosity = 1.0;  // slow sliding: viscous regime, eta |v_t|
  f.setZero();
  twoVertices(p).addForces(Eigen::VectorXd::Zero(6), v, f);
  EXPECT_DOUBLE_EQ(f[3], -2.0);
}

// The potential whose gradient the spring's force is: k d^2 / 2 for the vertex 0.01 below
// the ground, and central differences of it equal minus the force at random states that
// cross a plane and a sphere (tolerance: the differences' truncation, O(eps^2) = 1e-12
// relative, and round-off 1e-16 / eps; 1e-7 of the force's size covers both).
TEST(PenaltyContact, EnergyIsThePotentialOfTheSpringForce) {
  PenaltyContactParameters p;
  p.stiffness = 1000;
  const PenaltyContact ground = twoVertices(p);
  EXPECT_DOUBLE_EQ(ground.energy(Eigen::VectorXd::Zero(6)), 0.5 * 1000 * 0.01 * 0.01);
  Eigen::VectorXd lifted = Eigen::VectorXd::Zero(6);
  lifted[4] = 0.02;  // out of the ground: no potential
  EXPECT_EQ(ground.energy(lifted), 0.0);
  const PenaltyContact both = twoVertices(p, {ContactSphere{Eigen::Vector3d(0.05, 0.02, 0), 0.1}});
  std::srand(7);
  int compared = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::VectorXd u = 0.05 * Eigen::VectorXd::Random(6);
    if (both.activeContacts(u) == 0) continue;
    Eigen::VectorXd force = Eigen::VectorXd::Zero(6);
    both.addForces(u, Eigen::VectorXd::Zero(6), force);
    const double eps = 1e-6;
    for (int dof = 0; dof < 6; ++dof) {
      Eigen::VectorXd plus = u, minus = u;
      plus[dof] += eps;
      minus[dof] -= eps;
      const double slope = (both.energy(plus) - both.energy(minus)) / (2 * eps);
      EXPECT_NEAR(slope, -force[dof], 1e-7 * std::max(1.0, force.norm())) << "trial " << trial << " dof " << dof;
    }
    ++compared;
  }
  EXPECT_GE(compared, 5);
}

TEST(PenaltyContact, SpheresAndSubsets) {
  PenaltyContactParameters p;
  p.stiffness = 10;
  const PenaltyContact contact = twoVertices(p, {ContactSphere{Eigen::Vector3d(0, 1.5, 0), 0.6}});
  Eigen::VectorXd f = Eigen::VectorXd::Zero(6);
  contact.addForces(Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(6), f);
  EXPECT_NEAR(f[1], -10 * 0.1, 1e-12);  // pushed out of the sphere, downwards
  f.setZero();
  const std::vector<int> onlySecond{1};
  contact.addForces(Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(6), f, &onlySecond);
  EXPECT_EQ(f[1], 0.0);
  EXPECT_GT(f[4], 0.0);
}

TEST(PenaltyContact, PlaneNormalIsNormalised) {
  PenaltyContactParameters p;
  Eigen::Matrix3Xd rest(3, 1);
  rest.col(0) = Eigen::Vector3d(0, 0.5, 0);
  // 2 y >= 2 is the plane y = 1: the vertex is 0.5 below it.
  const PenaltyContact contact(rest, {ContactPlane{Eigen::Vector3d(0, 2, 0), 2.0}}, {}, p);
  EXPECT_NEAR(contact.maxPenetration(Eigen::VectorXd::Zero(3)), 0.5, 1e-15);
}

TEST(PenaltyContact, RejectsBadParameters) {
  PenaltyContactParameters p;
  p.stiffness = 0;
  EXPECT_THROW(twoVertices(p), ValidationError);
  p.stiffness = 1;
  p.friction = -1;
  EXPECT_THROW(twoVertices(p), ValidationError);
  p.friction = 0;
  EXPECT_THROW(twoVertices(p, {ContactSphere{Eigen::Vector3d::Zero(), 0.0}}), ValidationError);
  Eigen::Matrix3Xd rest = Eigen::Matrix3Xd::Zero(3, 1);
  EXPECT_THROW(PenaltyContact(rest, {ContactPlane{Eigen::Vector3d::Zero(), 0}}, {}, PenaltyContactParameters{}),
               ValidationError);
}

// jacobian(): each block against central differences of addForces in u and in v, for a
// vertex in a plane and one in a sphere, with normal damping and friction in its viscous
// and its sliding regime (states chosen away from the kinks, so the force is smooth there).
// Tolerance 1e-6 of the block's norm: central differences with a step of 1e-7 of the
// state's scale err by about step^2 times the third derivative (curvature 1/0.3 here) plus
// round-off of 1e-16 / 1e-7 of the force.
TEST(PenaltyContact, JacobianMatchesFiniteDifferencesOfTheForces) {
  Eigen::Matrix3Xd rest(3, 3);
  rest.col(0) = Eigen::Vector3d(0.1, -0.02, 0.05);  // in the ground
  rest.col(1) = Eigen::Vector3d(2.0, 0.9, 0.1);     // in the sphere (centre (2, 1.2, 0), radius 0.35)
  rest.col(2) = Eigen::Vector3d(0, 3, 0);           // free
  const ContactSphere sphere{Eigen::Vector3d(2.0, 1.2, 0.0), 0.35};
  Eigen::VectorXd u = Eigen::VectorXd::Zero(9), v = Eigen::VectorXd::Zero(9);
  u.segment<3>(0) = Eigen::Vector3d(0.01, 0.003, -0.02);
  u.segment<3>(3) = Eigen::Vector3d(0.02, -0.01, 0.03);
  v.segment<3>(0) = Eigen::Vector3d(0.3, -0.2, 0.1);
  v.segment<3>(3) = Eigen::Vector3d(-0.4, 0.25, 0.2);
  for (const double viscosity : {1.0, 1e4}) {  // viscous (eta |v_t| < mu f_n), then sliding
    PenaltyContactParameters p;
    p.stiffness = 2000;
    p.damping = 15;
    p.friction = 0.4;
    p.frictionViscosity = viscosity;
    const PenaltyContact contact(rest, {ContactPlane{}}, {sphere}, p);
    const PenaltyContactJacobian jacobian = contact.jacobian(u, v);
    ASSERT_EQ(jacobian.vertices, (std::vector<int>{0, 1}));
    ASSERT_EQ(jacobian.stiffness.size(), 2u);
    ASSERT_EQ(jacobian.damping.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
      const int vertex = jacobian.vertices[k];
      Eigen::Matrix3d stiffness, damping;
      for (int j = 0; j < 3; ++j) {
        for (const bool inVelocity : {false, true}) {
          const double step = 1e-7 * (inVelocity ? 1.0 : 0.1);
          Eigen::VectorXd plusU = u, minusU = u, plusV = v, minusV = v;
          Eigen::VectorXd& plus = inVelocity ? plusV : plusU;
          Eigen::VectorXd& minus = inVelocity ? minusV : minusU;
          plus[3 * vertex + j] += step;
          minus[3 * vertex + j] -= step;
          Eigen::VectorXd fPlus = Eigen::VectorXd::Zero(9), fMinus = Eigen::VectorXd::Zero(9);
          contact.addForces(plusU, plusV, fPlus);
          contact.addForces(minusU, minusV, fMinus);
          const Eigen::Vector3d column = -(fPlus - fMinus).segment<3>(3 * vertex) / (2.0 * step);
          (inVelocity ? damping : stiffness).col(j) = column;
        }
      }
      EXPECT_LE((jacobian.stiffness[k] - stiffness).norm(), 1e-6 * stiffness.norm())
          << "vertex " << vertex << ", eta " << viscosity << "\n"
          << jacobian.stiffness[k] << "\n"
          << stiffness;
      EXPECT_LE((jacobian.damping[k] - damping).norm(), 1e-6 * damping.norm())
          << "vertex " << vertex << ", eta " << viscosity << "\n"
          << jacobian.damping[k] << "\n"
          << damping;
    }
  }
  // A vertex leaving so fast that damping would pull: no force, so no entry.
  PenaltyContactParameters p;
  p.stiffness = 2000;
  p.damping = 15;
  const PenaltyContact contact(rest, {ContactPlane{}}, {}, p);
  Eigen::VectorXd leaving = Eigen::VectorXd::Zero(9);
  leaving[1] = 10.0;
  EXPECT_TRUE(contact.jacobian(u, leaving).vertices.empty());
  // A plane without damping or friction: exactly k n n^T, and nothing in v.
  p.damping = 0;
  const PenaltyContactJacobian plain = PenaltyContact(rest, {ContactPlane{}}, {}, p).jacobian(u, v);
  ASSERT_EQ(plain.vertices, (std::vector<int>{0}));
  Eigen::Matrix3d expected = Eigen::Matrix3d::Zero();
  expected(1, 1) = 2000;
  EXPECT_EQ(plain.stiffness[0], expected);
  EXPECT_EQ(plain.damping[0], Eigen::Matrix3d::Zero());
}

}  // namespace
}  // namespace asyncfem
