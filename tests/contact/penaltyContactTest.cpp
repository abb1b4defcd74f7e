// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>

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

}  // namespace
}  // namespace asyncfem
