// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/problem/loads.hpp>
#include <limits>
#include <memory>
#include <vector>

namespace asyncfem {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

VertexLoad pull(std::vector<int> vertices, Eigen::Vector3d force, double start, double end) {
  VertexLoad load;
  load.vertices = std::move(vertices);
  load.perVertex = force;
  load.start = start;
  load.end = end;
  return load;
}

TEST(Loads, EvaluatesConstantAndWindowsAtTheirTimes) {
  Loads loads;
  loads.addConstant(Eigen::VectorXd::Constant(9, 1.0));
  loads.addWindow(pull({0, 2}, Eigen::Vector3d(1, 2, 3), 0.1, 0.3));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(9);
  Eigen::VectorXd before = zero, during = zero, atEnd = zero;
  loads.addTo(0.05, zero, zero, before);
  loads.addTo(0.1, zero, zero, during);  // the start is inside [start, end)
  loads.addTo(0.3, zero, zero, atEnd);   // the end is not
  EXPECT_EQ(before, Eigen::VectorXd::Constant(9, 1.0));
  EXPECT_EQ(atEnd, Eigen::VectorXd::Constant(9, 1.0));
  EXPECT_EQ(during.segment<3>(0), Eigen::Vector3d(2, 3, 4));
  EXPECT_EQ(during.segment<3>(3), Eigen::Vector3d(1, 1, 1));
  EXPECT_EQ(during.segment<3>(6), Eigen::Vector3d(2, 3, 4));
}

TEST(Loads, ImpulseWindowsAreOpenOnTheLeft) {
  VertexLoad impulse = pull({1}, Eigen::Vector3d(5, 0, 0), 0.5, 1.5);
  impulse.leftOpen = true;
  EXPECT_FALSE(impulse.active(0.5));
  EXPECT_TRUE(impulse.active(1.0));
  EXPECT_TRUE(impulse.active(1.5));
}

TEST(Loads, BreakpointsLastChangeAndConstantPart) {
  Loads loads;
  loads.addConstant(Eigen::VectorXd::Constant(6, 2.0));
  loads.addWindow(pull({0}, Eigen::Vector3d(1, 0, 0), 0.2, 0.4));
  loads.addWindow(pull({1}, Eigen::Vector3d(0, 1, 0), 0.3, inf));  // never ends: constant after 0.3
  EXPECT_EQ(loads.breakpoints(), (std::vector<double>{0.2, 0.3, 0.4}));
  EXPECT_DOUBLE_EQ(loads.lastChange(), 0.4);
  Eigen::VectorXd expected = Eigen::VectorXd::Constant(6, 2.0);
  expected[4] += 1.0;
  EXPECT_EQ(loads.constantPart(6), expected);
  // The constant part is what acts at any time after the last change.
  Eigen::VectorXd late = Eigen::VectorXd::Zero(6);
  loads.addTo(10.0, late, late, late);
  EXPECT_EQ(late, expected);
}

TEST(Loads, ZeroOrEmptyWindowsAreDroppedAndBadWindowsRefused) {
  Loads loads;
  loads.addWindow(pull({0}, Eigen::Vector3d::Zero(), 0.0, 1.0));
  loads.addWindow(pull({}, Eigen::Vector3d(1, 0, 0), 0.0, 1.0));
  EXPECT_TRUE(loads.empty());
  EXPECT_THROW(loads.addWindow(pull({0}, Eigen::Vector3d(1, 0, 0), 2.0, 1.0)), ValidationError);
  loads.addConstant(Eigen::VectorXd::Zero(6));
  EXPECT_THROW(loads.addConstant(Eigen::VectorXd::Zero(9)), ValidationError);
}

TEST(Loads, ContactMakesTheLastChangeInfinite) {
  Loads loads;
  Eigen::Matrix3Xd rest(3, 1);
  rest << 0, 0, 1;
  ContactPlane ground;
  loads.setContact(std::make_shared<PenaltyContact>(rest, std::vector<ContactPlane>{ground},
                                                    std::vector<ContactSphere>{}, PenaltyContactParameters{}));
  EXPECT_EQ(loads.lastChange(), inf);
  EXPECT_EQ(loads.lastWindowChange(), 0.0);  // contact aside, nothing changes
  loads.addWindow(pull({0}, Eigen::Vector3d(1, 0, 0), 0.1, 0.4));
  EXPECT_EQ(loads.lastChange(), inf);
  EXPECT_DOUBLE_EQ(loads.lastWindowChange(), 0.4);
  EXPECT_FALSE(loads.empty());
}

// addTo at a few vertices (what the asynchronous integrator's substeps ask for): the same
// values at those vertices as the whole-body addTo, to the bit (the same additions in the
// same order), and every other entry left as it was. Constant part, two windows (one of
// them partly on the subset) and a ground that two of the vertices are inside.
TEST(Loads, AddToAtVerticesMatchesTheWholeBody) {
  Eigen::Matrix3Xd rest(3, 5);
  rest << 0, 1, 2, 3, 4, 0.5, -0.1, 0.3, -0.2, 0.4, 0, 0, 0, 0, 0;
  PenaltyContactParameters parameters;
  parameters.stiffness = 1e3;
  parameters.damping = 2.0;
  parameters.friction = 0.3;
  auto contact = std::make_shared<PenaltyContact>(rest, std::vector<ContactPlane>{ContactPlane{}},
                                                  std::vector<ContactSphere>{}, parameters);
  Loads loads;
  loads.addConstant(Eigen::VectorXd::LinSpaced(15, 0.1, 1.5));
  loads.addWindow(pull({0, 1, 3}, Eigen::Vector3d(1, 2, 3), 0.0, 1.0));
  loads.addWindow(pull({2, 4}, Eigen::Vector3d(-1, 0.5, 0.25), 0.0, inf));
  loads.setContact(contact);
  const Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(15, -0.01, 0.02);
  const Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(15, 0.3, -0.2);
  Eigen::VectorXd whole = Eigen::VectorXd::Zero(15);
  loads.addTo(0.5, u, v, whole);
  const std::vector<int> some{1, 3, 4};
  Eigen::VectorXd part = Eigen::VectorXd::Constant(15, 7.0);
  for (int vertex : some) part.segment<3>(3 * vertex).setZero();
  loads.addTo(0.5, u, v, some, part);
  ASSERT_GT(contact->activeContacts(u), 0);
  for (int vertex = 0; vertex < 5; ++vertex) {
    const bool listed = vertex == 1 || vertex == 3 || vertex == 4;
    for (int c = 0; c < 3; ++c) EXPECT_EQ(part[3 * vertex + c], listed ? whole[3 * vertex + c] : 7.0) << vertex;
  }
  // Only the listed vertices' state is read (what DynamicSystem::externalForceAt allows its
  // callers to rely on): the others may hold another state, here one deep in the ground.
  Eigen::VectorXd otherU = u, otherV = v;
  for (int vertex : {0, 2}) {
    otherU.segment<3>(3 * vertex).setConstant(-5.0);
    otherV.segment<3>(3 * vertex).setConstant(9.0);
  }
  Eigen::VectorXd again = Eigen::VectorXd::Constant(15, 7.0);
  for (int vertex : some) again.segment<3>(3 * vertex).setZero();
  loads.addTo(0.5, otherU, otherV, some, again);
  EXPECT_EQ(again, part);
}

}  // namespace
}  // namespace asyncfem
