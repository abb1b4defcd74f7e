// SPDX-License-Identifier: BSD-3-Clause
// Conservative time of impact (docs/barrier-contact.md, Eq. B5) on trajectories whose first
// contact is known: the reported time is never later, the pair is still apart there, and a
// pair that stays apart reports no impact.
#include <gtest/gtest.h>

#include <asyncfem/barrier/additiveCcd.hpp>
#include <asyncfem/collision/distance.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <limits>
#include <random>

namespace asyncfem {
namespace {

using Points = Eigen::Matrix<double, 3, 4>;

double pointTriangleGap(const Points& x) {
  return std::sqrt(pointTriangleDistanceSquared(x.col(0), x.col(1), x.col(2), x.col(3)));
}
double edgeEdgeGap(const Points& x) {
  return std::sqrt(edgeEdgeDistanceSquared(x.col(0), x.col(1), x.col(2), x.col(3)));
}

Points triangleWithPoint(const Eigen::Vector3d& p) {
  Points x;
  x << p, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0);
  return x;
}

// A point falling straight onto the face: first contact at t* = 0.6 (height 0.3, speed
// 0.5). The time reported is at most t* and, with gapFraction 0.1, stops within the last
// 10% of the gap: at least 0.9 t* minus round-off; the pair is apart there.
TEST(AdditiveCcd, PointOntoFace) {
  const Points start = triangleWithPoint({0.25, 0.25, 0.3});
  Points motion = Points::Zero();
  motion.col(0) = Eigen::Vector3d(0, 0, -0.5);
  const TimeOfImpact hit = pointTriangleTimeOfImpact(start, motion);
  ASSERT_TRUE(hit.impact);
  EXPECT_LE(hit.stepFraction, 0.6);
  EXPECT_GE(hit.stepFraction, 0.9 * 0.6 - 1e-12);
  EXPECT_GT(pointTriangleGap(start + hit.stepFraction * motion), 0.0);
  // The same relative motion with the triangle moving up instead: the same answer.
  Points lifted = Points::Zero();
  for (int k = 1; k < 4; ++k) lifted.col(k) = Eigen::Vector3d(0, 0, 0.5);
  const TimeOfImpact mirrored = pointTriangleTimeOfImpact(start, lifted);
  ASSERT_TRUE(mirrored.impact);
  EXPECT_NEAR(mirrored.stepFraction, hit.stepFraction, 1e-12);
}

// Stopping short: the point falls, but only half way to the face: no impact. Grazing: the
// point slides past at height 0.01 over the face, within a tenth of its start gap (0.5), so
// the step is cut (a line search queries again) where the point is still above the face;
// queried again from there with the rest of the motion, it gets past the face.
TEST(AdditiveCcd, PairsThatStayApart) {
  Points slide = Points::Zero();
  slide.col(0) = Eigen::Vector3d(2.0, 0, 0);
  const Points grazing = triangleWithPoint({-0.5, 0.2, 0.01});
  const TimeOfImpact cut = pointTriangleTimeOfImpact(grazing, slide);
  ASSERT_TRUE(cut.impact);
  EXPECT_GT(cut.stepFraction, 0.0);
  EXPECT_GT(pointTriangleGap(grazing + cut.stepFraction * slide), 0.0);
  double reached = cut.stepFraction;
  for (int query = 0; query < 100 && reached < 1.0; ++query) {
    const TimeOfImpact next = pointTriangleTimeOfImpact(grazing + reached * slide, (1.0 - reached) * slide);
    reached = next.impact ? reached + (1.0 - reached) * next.stepFraction : 1.0;
  }
  EXPECT_EQ(reached, 1.0);
  Points half = Points::Zero();
  half.col(0) = Eigen::Vector3d(0, 0, -0.15);
  EXPECT_FALSE(pointTriangleTimeOfImpact(triangleWithPoint({0.25, 0.25, 0.3}), half).impact);
  // No relative motion at all (the whole pair translated): no impact, one distance query.
  Points together = Points::Zero();
  for (int k = 0; k < 4; ++k) together.col(k) = Eigen::Vector3d(0.3, -2, 1);
  EXPECT_FALSE(pointTriangleTimeOfImpact(triangleWithPoint({0.25, 0.25, 0.3}), together).impact);
}

// The point moves onto an edge of the triangle (vertex-on-edge contact at t* = 0.5), and
// two edges meet: crossing at right angles (t* = 0.4) and parallel ones (t* = 0.25).
TEST(AdditiveCcd, VertexOnEdgeAndEdgeEdge) {
  Points motion = Points::Zero();
  motion.col(0) = Eigen::Vector3d(0, 0.4, -0.2);  // from (0.5, -0.2, 0.1) to the edge ab at t = 0.5
  const TimeOfImpact onEdge = pointTriangleTimeOfImpact(triangleWithPoint({0.5, -0.2, 0.1}), motion);
  ASSERT_TRUE(onEdge.impact);
  EXPECT_LE(onEdge.stepFraction, 0.5);
  EXPECT_GE(onEdge.stepFraction, 0.45 - 1e-12);

  Points edges;
  edges << Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, -1, 0.2), Eigen::Vector3d(0, 1, 0.2);
  Points down = Points::Zero();
  down.col(2) = down.col(3) = Eigen::Vector3d(0, 0, -0.5);
  const TimeOfImpact crossing = edgeEdgeTimeOfImpact(edges, down);
  ASSERT_TRUE(crossing.impact);
  EXPECT_LE(crossing.stepFraction, 0.4);
  EXPECT_GE(crossing.stepFraction, 0.36 - 1e-12);
  EXPECT_GT(edgeEdgeGap(edges + crossing.stepFraction * down), 0.0);

  Points parallel;
  parallel << Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0.2, 0.1, 0),
      Eigen::Vector3d(0.8, 0.1, 0);
  Points closing = Points::Zero();
  closing.col(2) = closing.col(3) = Eigen::Vector3d(0, -0.4, 0);
  const TimeOfImpact side = edgeEdgeTimeOfImpact(parallel, closing);
  ASSERT_TRUE(side.impact);
  EXPECT_LE(side.stepFraction, 0.25);
  EXPECT_GE(side.stepFraction, 0.225 - 1e-12);
}

// Random moving triangles and a point built to pass through the triangle's interior at a
// random time t*: a contact at t*, so the first contact is no later. The reported time
// never exceeds t*, and the pair is apart there (500 trajectories, the point's path and
// every vertex's moving).
TEST(AdditiveCcd, NeverLaterThanAKnownContact) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0), unit(0.0, 1.0);
  int impacts = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Points start, motion;
    for (int k = 1; k < 4; ++k) {
      start.col(k) = Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
      motion.col(k) = 0.5 * Eigen::Vector3d(uniform(random), uniform(random), uniform(random));
    }
    const double contact = 0.05 + 0.9 * unit(random);
    double u = unit(random), v = unit(random);
    if (u + v > 1.0) {
      u = 1.0 - u;
      v = 1.0 - v;
    }
    const Points at = start + contact * motion;
    const Eigen::Vector3d q = at.col(1) + u * (at.col(2) - at.col(1)) + v * (at.col(3) - at.col(1));
    const Eigen::Vector3d velocity(uniform(random), uniform(random), uniform(random));
    start.col(0) = q - contact * velocity;
    motion.col(0) = velocity;
    const TimeOfImpact hit = pointTriangleTimeOfImpact(start, motion);
    ASSERT_TRUE(hit.impact) << "trial " << trial;
    ++impacts;
    EXPECT_LE(hit.stepFraction, contact) << "trial " << trial;
    if (hit.stepFraction > 0.0) {
      EXPECT_GT(pointTriangleGap(start + hit.stepFraction * motion), 0.0) << "trial " << trial;
    }
  }
  EXPECT_EQ(impacts, 500);
}

// Bad input: options out of range and non-finite positions are errors, not answers; a pair
// that starts in contact reports an impact at t = 0.
TEST(AdditiveCcd, BadInputAndStartingInContact) {
  const Points start = triangleWithPoint({0.25, 0.25, 0.3});
  AdditiveCcdOptions bad;
  bad.gapFraction = 1.0;
  EXPECT_THROW(pointTriangleTimeOfImpact(start, Points::Zero(), bad), ValidationError);
  Points nan = Points::Zero();
  nan(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(pointTriangleTimeOfImpact(start, nan), NumericalError);
  const TimeOfImpact touching = pointTriangleTimeOfImpact(triangleWithPoint({0.25, 0.25, 0.0}), Points::Zero());
  EXPECT_TRUE(touching.impact);
  EXPECT_EQ(touching.stepFraction, 0.0);
}

}  // namespace
}  // namespace asyncfem
