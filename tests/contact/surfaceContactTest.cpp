// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/contact/surfaceContact.hpp>
#include <asyncfem/core/error.hpp>
#include <random>

namespace asyncfem {
namespace {

// Two tetrahedra as one mesh of two objects: A's top corner (vertex 3) points up at B,
// whose bottom face (vertices 4, 5, 6) lies at height `gap` above it.
TetMesh twoTets(double gap) {
  Eigen::Matrix3Xd rest(3, 8);
  rest.col(0) << -1, -1, -1;
  rest.col(1) << 1, -1, -1;
  rest.col(2) << 0, -1, 1;
  rest.col(3) << 0.1, 0, 0.05;
  rest.col(4) << -1, gap, -1;
  rest.col(5) << 0, gap, 1;
  rest.col(6) << 1, gap, -1;
  rest.col(7) << 0, gap + 1, 0;
  Eigen::Matrix4Xi elements(4, 2);
  elements.col(0) << 0, 1, 2, 3;
  elements.col(1) << 4, 5, 6, 7;
  // Orient both positively (the mesh checks it).
  for (int e = 0; e < 2; ++e) {
    const auto x = [&](int c) { return Eigen::Vector3d(rest.col(elements(c, e))); };
    if ((x(1) - x(0)).cross(x(2) - x(0)).dot(x(3) - x(0)) < 0) std::swap(elements(1, e), elements(2, e));
  }
  return TetMesh(rest, elements, {Material{"m", 1000, 1e6, 0.3}}, {0, 0});
}

const std::vector<int> kTwoObjects{0, 0, 0, 0, 1, 1, 1, 1};

SurfaceContact bodies(double gap, double thickness, double damping = 0.0, double friction = 0.0) {
  SurfaceContactOptions options;
  options.thickness = thickness;
  return SurfaceContact(twoTets(gap), kTwoObjects, {}, options, 1000.0, damping, friction, 10.0);
}

// Velocities in [-1, 1] for the two tets' eight vertices.
Eigen::VectorXd randomVelocities(unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> noise(-1.0, 1.0);
  Eigen::VectorXd v(24);
  for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = noise(random);
  return v;
}

TEST(SurfaceContact, VertexUnderAFacePushesApartWithStiffnessTimesDepth) {
  // Vertex 3 at height 0, B's bottom face at 0.05: gap 0.05 in a layer of 0.1.
  const SurfaceContact contact = bodies(0.05, 0.1);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(24);
  contact.addForces(0.0, Eigen::VectorXd::Zero(24), Eigen::VectorXd::Zero(24), f);
  // k (dhat - d) = 1000 * 0.05 = 50 down on the vertex (the only pair: the face is flat and
  // its edges are farther than the layer from A's edges), up on the face, split by the
  // barycentric weights.
  EXPECT_NEAR(f[3 * 3 + 1], -50.0, 1e-9);
  EXPECT_NEAR(f[3 * 4 + 1] + f[3 * 5 + 1] + f[3 * 6 + 1], 50.0, 1e-9);
  EXPECT_NEAR(contact.maxDepth(0.0, Eigen::VectorXd::Zero(24)), 0.05, 1e-12);
  EXPECT_NEAR(contact.energy(0.0, Eigen::VectorXd::Zero(24)), 0.5 * 1000 * 0.05 * 0.05, 1e-12);
}

TEST(SurfaceContact, ForcesAreMinusTheEnergyGradient) {
  // A state with several pairs (vertex-face, edge-edge) well inside the layer: central
  // differences of the energy with step 1e-7 have truncation error O(k step^2) and
  // round-off O(E eps / step) ~ 1e-9, far below the 1e-6 tolerance.
  const SurfaceContact contact = bodies(0.1, 0.7);
  std::mt19937 random(7);
  std::uniform_real_distribution<double> noise(-0.01, 0.01);
  Eigen::VectorXd u(24);
  for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = noise(random);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(24);
  contact.addForces(0.0, u, Eigen::VectorXd::Zero(24), f);
  ASSERT_GT(contact.pairs(0.0, u).size(), 3u);
  const double step = 1e-7;
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    Eigen::VectorXd plus = u, minus = u;
    plus[i] += step;
    minus[i] -= step;
    const double derivative = (contact.energy(0.0, plus) - contact.energy(0.0, minus)) / (2 * step);
    EXPECT_NEAR(f[i], -derivative, 1e-6 * std::max(1.0, std::abs(f[i]))) << "dof " << i;
  }
}

// The dense 3n x 3n matrix of a Jacobian's stiffness (or damping) blocks and couplings.
Eigen::MatrixXd denseOf(const VertexJacobian& jacobian, int numVertices, bool damping) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(3 * numVertices, 3 * numVertices);
  for (std::size_t k = 0; k < jacobian.vertices.size(); ++k) {
    out.block<3, 3>(3 * jacobian.vertices[k], 3 * jacobian.vertices[k]) +=
        damping ? jacobian.damping[k] : jacobian.stiffness[k];
  }
  for (const VertexCoupling& coupling : jacobian.couplings) {
    const Eigen::Matrix3d normalBlock = coupling.direction * coupling.direction.transpose();
    const double scale = damping ? coupling.damping : coupling.stiffness;
    for (std::size_t i = 0; i < 4; ++i) {
      for (std::size_t j = 0; j < 4; ++j) {
        if (coupling.vertices[i] < 0 || coupling.vertices[j] < 0) continue;
        out.block<3, 3>(3 * coupling.vertices[i], 3 * coupling.vertices[j]) +=
            scale * coupling.weights[i] * coupling.weights[j] * normalBlock;
      }
    }
  }
  return out;
}

TEST(SurfaceContact, CoupledJacobianIsTheForceDerivativeWithItsOffDiagonalBlocks) {
  // Vertex 3 under B's face, 1e-4 inside a layer of 0.1 (one vertex-face pair between two
  // bodies, k = 1000, c = 50), moving. The coupled Jacobian k (w w^T) (x) N N^T leaves out
  // only the turning of N with the face, k (dhat - s) d^2 s / dx^2 = 1000 * 1e-4 * O(1 /
  // edge) ~ 0.1 here, against entries k w_i w_j of up to 1000: central differences of the
  // force (step 1e-6, error O(k step) ~ 1e-3) agree to 0.5. The damping part
  // c (w w^T) (x) N N^T is exact (the force is linear in v), to round-off.
  const double k = 1000.0;
  const SurfaceContact contact = bodies(0.0999, 0.1, 50.0);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(24);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(24);
  v[3 * 3 + 1] = 0.001;  // closing slowly: the damping lowers F but does not clamp it
  ASSERT_EQ(contact.pairs(0.0, u).size(), 1u);
  VertexJacobian coupled;
  contact.addCoupledJacobian(0.0, u, v, coupled);
  ASSERT_EQ(coupled.couplings.size(), 1u);
  EXPECT_TRUE(coupled.vertices.empty());
  const Eigen::MatrixXd stiffness = denseOf(coupled, 8, false);
  const Eigen::MatrixXd damping = denseOf(coupled, 8, true);
  const auto forceAt = [&](const Eigen::VectorXd& du, const Eigen::VectorXd& dv) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(24);
    contact.addForces(0.0, u + du, v + dv, f);
    return f;
  };
  const double step = 1e-6;
  Eigen::MatrixXd differenceU(24, 24), differenceV(24, 24);
  for (Eigen::Index j = 0; j < 24; ++j) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(24);
    e[j] = step;
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(24);
    differenceU.col(j) = -(forceAt(e, zero) - forceAt(-e, zero)) / (2 * step);
    differenceV.col(j) = -(forceAt(zero, e) - forceAt(zero, -e)) / (2 * step);
  }
  EXPECT_LE((stiffness - differenceU).cwiseAbs().maxCoeff(), 0.5);
  EXPECT_LE((damping - differenceV).cwiseAbs().maxCoeff(), 1e-6);
  // The blocks between the vertex and the face's corners are there and large (the
  // per-vertex bound has none): -k w_3 b_i in (y, y), about -k / 3 each.
  for (const int corner : {4, 5, 6}) {
    EXPECT_LT(stiffness(3 * 3 + 1, 3 * corner + 1), -0.1 * k);
    EXPECT_NEAR(stiffness(3 * 3 + 1, 3 * corner + 1), differenceU(3 * 3 + 1, 3 * corner + 1), 0.5);
  }
  // The bound (addJacobian) is the couplings' Gershgorin bound: its diagonal blocks are at
  // least the coupled ones' (here S = 2: |w| sums to 1 on each body).
  VertexJacobian bound;
  contact.addJacobian(0.0, u, v, bound);
  const Eigen::MatrixXd bounded = denseOf(bound, 8, false);
  for (int vertex : {3, 4, 5, 6}) {
    EXPECT_NEAR(bounded(3 * vertex + 1, 3 * vertex + 1), 2.0 * std::sqrt(stiffness(3 * vertex + 1, 3 * vertex + 1) * k),
                1e-9 * k);
  }
}

TEST(SurfaceContact, ForcesBetweenBodiesSumToZeroWithDampingAndFriction) {
  const SurfaceContact contact = bodies(0.02, 0.3, 50.0, 0.4);
  const Eigen::VectorXd v = randomVelocities(11);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(24);
  contact.addForces(0.0, Eigen::VectorXd::Zero(24), v, f);
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  double size = 0.0;
  for (int vertex = 0; vertex < 8; ++vertex) {
    total += f.segment<3>(3 * vertex);
    size += f.segment<3>(3 * vertex).norm();
  }
  ASSERT_GT(size, 0.0);
  // Each pair's weights sum to zero: the total is round-off of a few terms.
  EXPECT_LE(total.norm(), 1e-14 * size);
}

TEST(SurfaceContact, AVertexBehindAClosedObstacleFaceIsPushedOut) {
  // One tetrahedron over a closed obstacle (a tetrahedron below it, faces out): its lowest
  // vertex 0.02 below the obstacle's top face still feels the force outward, k (dhat + 0.02).
  Eigen::Matrix3Xd rest(3, 4);
  rest.col(0) << 0.2, -0.02, 0.1;
  rest.col(1) << 1.2, 0.5, 0.1;
  rest.col(2) << 0.2, 0.5, 1.1;
  rest.col(3) << 0.4, 1.5, 0.3;
  Eigen::Matrix4Xi element(4, 1);
  element << 0, 1, 2, 3;
  if ((rest.col(1) - rest.col(0)).cross(rest.col(2) - rest.col(0)).dot(rest.col(3) - rest.col(0)) < 0)
    std::swap(element(1, 0), element(2, 0));
  const TetMesh body(rest, element, {Material{"m", 1000, 1e6, 0.3}}, {0});
  MeshObstacle block;
  block.name = "block";
  block.vertices.resize(3, 4);
  block.vertices.col(0) << -2, 0, -2;
  block.vertices.col(1) << 2, 0, -2;
  block.vertices.col(2) << 0, 0, 3;
  block.vertices.col(3) << 0, -3, 0;
  block.triangles.resize(3, 4);
  // Outward: the top face (0, 2, 1) faces +y.
  block.triangles.col(0) << 0, 2, 1;
  block.triangles.col(1) << 0, 1, 3;
  block.triangles.col(2) << 1, 2, 3;
  block.triangles.col(3) << 2, 0, 3;
  SurfaceContactOptions options;
  options.thickness = 0.05;
  const SurfaceContact contact(body, {}, {block}, options, 1000.0, 0.0, 0.0, 1.0);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(12);
  contact.addForces(0.0, Eigen::VectorXd::Zero(12), Eigen::VectorXd::Zero(12), f);
  EXPECT_NEAR(f[1], 1000 * (0.05 + 0.02), 1e-9);
  EXPECT_NEAR(f.segment<3>(0).norm(), 1000 * (0.05 + 0.02), 1e-9);
  // The implicit block of a mesh vertex against an obstacle face is exact: k n n^T.
  VertexJacobian jacobian;
  contact.addJacobian(0.0, Eigen::VectorXd::Zero(12), Eigen::VectorXd::Zero(12), jacobian);
  ASSERT_EQ(jacobian.vertices, std::vector<int>{0});
  EXPECT_NEAR(jacobian.stiffness[0](1, 1), 1000.0, 1e-9);
  EXPECT_NEAR(jacobian.stiffness[0].norm(), 1000.0, 1e-9);
  // Open (two-sided) obstacle: the vertex is 0.02 from the face, behind or not: k (dhat - 0.02) toward -y.
  block.closed = false;
  const SurfaceContact open(body, {}, {block}, options, 1000.0, 0.0, 0.0, 1.0);
  f.setZero();
  open.addForces(0.0, Eigen::VectorXd::Zero(12), Eigen::VectorXd::Zero(12), f);
  EXPECT_NEAR(f[1], -1000 * (0.05 - 0.02), 1e-9);
}

TEST(SurfaceContact, TheRanksSplitTheForceAndItsCouplingsIntoWholePairs) {
  // B lowered into A's top so that several pairs are active (vertex-face, edge-edge), with
  // damping and friction; the ranks put the tets' vertices in three groups, so that pairs
  // join vertices of different ranks. Summed over the ranks present, the forces are addForces' (each pair's force
  // computed alike, added in another order: round-off of a few terms), and each rank's forces sum to zero (whole pairs,
  // every vertex of them, whatever its rank).
  const SurfaceContact contact = bodies(0.02, 0.3, 50.0, 0.4);
  const Eigen::VectorXd v = randomVelocities(5);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(24);
  for (int vertex = 4; vertex < 8; ++vertex) u[3 * vertex + 1] = -0.1;  // B lowered into A's top
  ASSERT_GE(contact.pairs(0.0, u).size(), 3U);
  Eigen::VectorXd whole = Eigen::VectorXd::Zero(24);
  contact.addForces(0.0, u, v, whole);
  const std::vector<int> rank{1, 0, 2, 0, 0, 1, 0, 0};
  Eigen::VectorXd summed = Eigen::VectorXd::Zero(24);
  std::size_t couplings = 0;
  int ranksWithForce = 0;
  for (int owner = 0; owner <= 2; ++owner) {
    Eigen::VectorXd part = Eigen::VectorXd::Zero(24);
    VertexJacobian jacobian;
    contact.addForcesOfRank(0.0, u, v, rank, owner, part, &jacobian);
    EXPECT_LE(part.reshaped(3, 8).rowwise().sum().norm(), 1e-13 * (1.0 + part.norm())) << "rank " << owner;
    if (part.norm() > 0.0) ++ranksWithForce;
    summed += part;
    for (const VertexCoupling& coupling : jacobian.couplings) {
      int highest = -1;
      for (const int vertex : coupling.vertices)
        if (vertex >= 0) highest = std::max(highest, rank[static_cast<std::size_t>(vertex)]);
      EXPECT_EQ(highest, owner);
    }
    couplings += jacobian.couplings.size();
  }
  ASSERT_GT(whole.norm(), 0.0);
  EXPECT_GE(ranksWithForce, 2);  // the split is not trivial
  EXPECT_LE((summed - whole).cwiseAbs().maxCoeff(), 1e-13 * whole.cwiseAbs().maxCoeff());
  VertexJacobian all;
  contact.addCoupledJacobian(0.0, u, v, all);
  EXPECT_EQ(couplings, all.couplings.size());
  Eigen::VectorXd part = Eigen::VectorXd::Zero(24);
  EXPECT_THROW(contact.addForcesOfRank(0.0, u, v, {0, 1}, 0, part), ValidationError);
}

TEST(SurfaceContact, ReusedCandidateListsGiveTheSameForces) {
  // One model evaluated first at a nearby state (its list then reused), one fresh: the
  // forces must be bit-identical, since only pairs closer than dhat contribute.
  const SurfaceContact warm = bodies(0.02, 0.3, 5.0, 0.2);
  const SurfaceContact fresh = bodies(0.02, 0.3, 5.0, 0.2);
  Eigen::VectorXd u = Eigen::VectorXd::Constant(24, 0.01), v = Eigen::VectorXd::Constant(24, 0.3);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(24);
  warm.addForces(0.0, Eigen::VectorXd::Zero(24), v, f);
  Eigen::VectorXd a = Eigen::VectorXd::Zero(24), b = Eigen::VectorXd::Zero(24);
  warm.addForces(0.0, u, v, a);
  fresh.addForces(0.0, u, v, b);
  EXPECT_EQ(warm.stats().detections, 1);  // the second evaluation reused the list
  EXPECT_EQ((a - b).cwiseAbs().maxCoeff(), 0.0);
}

TEST(SurfaceContact, SelfContactLeavesOutPairsCloseInTheRestShape) {
  // A layer thicker than the tetrahedra: every pair within one of them is closer than
  // dhat, but also within 2 dhat at rest, so none counts; between the two, pairs do.
  SurfaceContactOptions options;
  options.thickness = 1.5;
  options.self = true;
  options.betweenBodies = false;
  const SurfaceContact self(twoTets(0.02), kTwoObjects, {}, options, 1000.0, 0.0, 0.0, 1.0);
  EXPECT_TRUE(self.pairs(0.0, Eigen::VectorXd::Zero(24)).empty());
  options.betweenBodies = true;
  const SurfaceContact both(twoTets(0.02), kTwoObjects, {}, options, 1000.0, 0.0, 0.0, 1.0);
  const std::vector<SurfacePair> pairs = both.pairs(0.0, Eigen::VectorXd::Zero(24));
  ASSERT_FALSE(pairs.empty());
  for (const SurfacePair& pair : pairs) EXPECT_NE(kTwoObjects[pair.points[0]], kTwoObjects[pair.points[3]]);
}

TEST(RigidPath, InterpolatesLinearlyAndTurnsAtAConstantRate) {
  RigidKey start, end;
  start.time = 1.0;
  end.time = 3.0;
  end.translation = Eigen::Vector3d(2, 0, 0);
  end.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()));
  const RigidPath path({start, end});
  Eigen::Matrix3d rotation;
  Eigen::Vector3d translation, angularVelocity, velocity;
  path.placement(2.0, rotation, translation, angularVelocity, velocity);
  EXPECT_NEAR((translation - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((rotation - Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix()).norm(), 0.0, 1e-14);
  EXPECT_NEAR((angularVelocity - Eigen::Vector3d(0, 0, 0.5)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((velocity - Eigen::Vector3d(1, 0, 0)).norm(), 0.0, 1e-15);
  // A point's velocity matches the central difference of its position (step 1e-6:
  // truncation O(step^2) of a smooth motion, round-off 1e-16 / 1e-6).
  const Eigen::Vector3d x(0.3, -0.7, 0.2);
  Eigen::Matrix3d r0, r1;
  Eigen::Vector3d t0, t1, w, c;
  path.placement(2.3 - 1e-6, r0, t0, w, c);
  path.placement(2.3 + 1e-6, r1, t1, w, c);
  path.placement(2.3, rotation, translation, angularVelocity, velocity);
  const Eigen::Vector3d difference = ((r1 * x + t1) - (r0 * x + t0)) / 2e-6;
  EXPECT_NEAR((difference - (angularVelocity.cross(rotation * x) + velocity)).norm(), 0.0, 1e-8);
  // Held before the first key and after the last.
  path.placement(0.0, rotation, translation, angularVelocity, velocity);
  EXPECT_EQ(translation, Eigen::Vector3d::Zero());
  EXPECT_EQ(velocity, Eigen::Vector3d::Zero());
}

TEST(RigidPath, RefusesFewerThanTwoKeysAndTimesThatDoNotIncrease) {
  try {
    const RigidPath path({RigidKey{}});
    FAIL() << "one key was accepted";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("at least two keys (got 1)"), std::string::npos) << error.what();
  }
  EXPECT_THROW(RigidPath({RigidKey{}, RigidKey{}}), ValidationError);
}

TEST(PenaltyContact, AddsTheSurfaceContactToPlanes) {
  SurfaceContactOptions options;
  options.thickness = 0.1;
  const TetMesh mesh = twoTets(0.05);
  auto surfaces =
      std::make_shared<SurfaceContact>(mesh, kTwoObjects, std::vector<MeshObstacle>{}, options, 1000.0, 0.0, 0.0, 1.0);
  const PenaltyContact contact(mesh.restPositions(), {}, {}, PenaltyContactParameters{}, surfaces);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(24);
  contact.addForces(Eigen::VectorXd::Zero(24), Eigen::VectorXd::Zero(24), f);
  EXPECT_NEAR(f[3 * 3 + 1], -50.0, 1e-9);
  EXPECT_EQ(contact.activeContacts(Eigen::VectorXd::Zero(24)), 4);  // vertex 3 and the face's three
  EXPECT_FALSE(contact.timeDependent());
}

}  // namespace
}  // namespace asyncfem
