// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>

namespace asyncfem {
namespace {

std::shared_ptr<const TetMesh> beam() {
  BeamSpec spec;
  spec.cellsAlongLength = 6;
  return std::make_shared<const TetMesh>(makeBeamMesh(spec));
}

TEST(Problem, BuildsNothingUntilAsked) {
  const auto mesh = beam();
  ProblemSettings settings;
  settings.gravity = Eigen::Vector3d(0, -9.81, 0);
  const Problem problem(mesh, mesh->vertexSets().at("root"), settings);
  // The mesh, the boundary and the free DOFs cost no matrix.
  EXPECT_EQ(problem.freeDofs().numFixed(), 3 * static_cast<int>(mesh->vertexSets().at("root").size()));
  EXPECT_EQ(problem.assemblies(), 0);
  // Gravity M g needs M: asking for the loads assembles it, once.
  const auto& loads = problem.loads();
  EXPECT_EQ(problem.assemblies(), 1);
  (void)problem.massMatrix();
  EXPECT_EQ(problem.assemblies(), 1);
  // M g sums to the total weight on each axis (mass = density x volume; 1e-9 relative:
  // round-off of the element sums).
  const Eigen::VectorXd g = loads->constantPart(problem.numDofs());
  double weight = 0.0;
  for (Eigen::Index i = 1; i < g.size(); i += 3) weight += g[i];
  double mass = 0.0;
  for (Eigen::Index i = 0; i < problem.massMatrix().outerSize(); i += 3) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(problem.massMatrix(), i); it; ++it) {
      if (it.row() % 3 == 0) mass += it.value();
    }
  }
  EXPECT_NEAR(weight, -9.81 * mass, 1e-9 * 9.81 * mass);
}

TEST(Problem, DynamicSystemRunsAnIntegratorUnderTheLoads) {
  const auto mesh = beam();
  VertexLoad pull;
  pull.vertices = mesh->vertexSets().at("tip");
  pull.perVertex = Eigen::Vector3d(0, 10.0, 0);
  const Problem problem(mesh, mesh->vertexSets().at("root"), ProblemSettings{}, {pull});
  auto integrator = makeIntegrator("backward-euler", problem.dynamicSystem(), 0.01);
  EXPECT_EQ(problem.assemblies(), 2);  // M and K
  for (int i = 0; i < 5; ++i) integrator->step();
  // The pull lifts the tip; the root stays where it is.
  EXPECT_GT(integrator->displacement()[3 * pull.vertices.front() + 1], 0.0);
  EXPECT_EQ(integrator->displacement()[3 * mesh->vertexSets().at("root").front() + 1], 0.0);
}

// The hook that lets a multirate integrator evaluate the loads once per large step: true
// exactly for intervals that hold a window bound (gravity and windows that never close
// change nothing).
TEST(Problem, ExternalForceChangesWhereAWindowOpensOrCloses) {
  const auto mesh = beam();
  VertexLoad pull;
  pull.vertices = mesh->vertexSets().at("tip");
  pull.perVertex = Eigen::Vector3d(0, 10.0, 0);
  pull.start = 0.05;
  pull.end = 0.1;
  ProblemSettings settings;
  settings.gravity = Eigen::Vector3d(0, -9.81, 0);
  const DynamicSystem system = Problem(mesh, mesh->vertexSets().at("root"), settings, {pull}).dynamicSystem();
  ASSERT_TRUE(static_cast<bool>(system.externalForceChanges));
  EXPECT_FALSE(system.externalForceChanges(0.0, 0.04));
  EXPECT_TRUE(system.externalForceChanges(0.04, 0.05));  // opens at the interval's end
  EXPECT_TRUE(system.externalForceChanges(0.05, 0.06));  // opened at its start (left bound counts)
  EXPECT_FALSE(system.externalForceChanges(0.06, 0.09));
  EXPECT_TRUE(system.externalForceChanges(0.09, 0.12));
  EXPECT_FALSE(system.externalForceChanges(0.12, 10.0));
}

// Evaluating the loads once per large step where they are constant changes nothing: the
// asynchronous trajectory is bit for bit the one with an evaluation at every substep time,
// through a window that opens and closes inside large steps.
TEST(Problem, AsyncStepEvaluatesConstantLoadsOncePerLargeStep) {
  const auto mesh = beam();
  VertexLoad pull;
  pull.vertices = mesh->vertexSets().at("tip");
  pull.perVertex = Eigen::Vector3d(0, 40.0, 5.0);
  pull.start = 0.013;  // inside the second large step of 0.01
  pull.end = 0.047;    // inside the fifth
  ProblemSettings settings;
  settings.gravity = Eigen::Vector3d(0, -9.81, 0);
  const DynamicSystem system = Problem(mesh, mesh->vertexSets().at("root"), settings, {pull}).dynamicSystem();
  DynamicSystem everySubstep = system;
  everySubstep.externalForceChanges = nullptr;
  const std::vector<AsyncRegion> regions{{"tip", mesh->vertexSets().at("tip"), 8}};
  AsyncBackwardEuler once(system, 0.01, regions);
  AsyncBackwardEuler each(everySubstep, 0.01, regions);
  for (int k = 0; k < 8; ++k) {
    once.step();
    each.step();
    ASSERT_EQ(once.displacement(), each.displacement()) << "large step " << k;
    ASSERT_EQ(once.velocity(), each.velocity()) << "large step " << k;
  }
  EXPECT_GT(once.displacement().cwiseAbs().maxCoeff(), 0.0);
}

TEST(Problem, RefusesBadBoundaries) {
  const auto mesh = beam();
  std::vector<int> all(static_cast<std::size_t>(mesh->numVertices()));
  for (int v = 0; v < mesh->numVertices(); ++v) all[static_cast<std::size_t>(v)] = v;
  EXPECT_THROW(Problem(mesh, all, ProblemSettings{}), ValidationError);
  EXPECT_THROW(Problem(mesh, {mesh->numVertices()}, ProblemSettings{}), ValidationError);
  VertexLoad load;
  load.vertices = {-1};
  load.perVertex = Eigen::Vector3d::UnitX();
  EXPECT_THROW(Problem(mesh, {}, ProblemSettings{}, {load}), ValidationError);
}

// A vertex that no element uses has no mass or stiffness: it is held at rest (not a free
// DOF, so the matrices stay definite) without being counted as fixed; a mesh whose every
// vertex is fixed or unused is refused.
TEST(Problem, VerticesInNoElementAreHeldNotFixed) {
  const auto beamMesh = beam();
  Eigen::Matrix3Xd x(3, beamMesh->numVertices() + 1);
  x << beamMesh->restPositions(), Eigen::Vector3d(9, 9, 9);
  auto mesh = std::make_shared<TetMesh>(x, beamMesh->elements(), beamMesh->materials(), beamMesh->elementMaterials());
  const int stray = beamMesh->numVertices();
  const std::vector<int>& root = beamMesh->vertexSets().at("root");
  const Problem problem(mesh, root, ProblemSettings{});
  EXPECT_EQ(problem.unusedVertices(), std::vector<int>{stray});
  EXPECT_EQ(problem.fixedVertices(), root);
  EXPECT_EQ(problem.freeDofs().numFixed(), 3 * static_cast<int>(root.size() + 1));
  EXPECT_TRUE(problem.freeDofs().isFixed(3 * stray + 2));
  std::vector<int> held = root;
  held.push_back(stray);
  EXPECT_EQ(problem.heldVertices(), held);
  const std::vector<std::string> skipped = problem.skipped();
  EXPECT_NE(std::find(skipped.begin(), skipped.end(), "free DOFs of 1 vertex(es) that no element uses (held at rest)"),
            skipped.end());
  // Backward Euler factors M + h^2 K on the free DOFs: it steps (a zero row would not).
  VertexLoad pull;
  pull.vertices = beamMesh->vertexSets().at("tip");
  pull.perVertex = Eigen::Vector3d(0, 10.0, 0);
  const Problem pulled(mesh, root, ProblemSettings{}, {pull});
  auto integrator = makeIntegrator("backward-euler", pulled.dynamicSystem(), 0.01);
  integrator->step();
  EXPECT_GT(integrator->displacement()[3 * pull.vertices.front() + 1], 0.0);
  EXPECT_TRUE(integrator->displacement().segment<3>(3 * stray).isZero(0.0));

  std::vector<int> allUsed(static_cast<std::size_t>(stray));
  for (int v = 0; v < stray; ++v) allUsed[static_cast<std::size_t>(v)] = v;
  EXPECT_THROW(Problem(mesh, allUsed, ProblemSettings{}), ValidationError);
}

TEST(Problem, SkippedWorkIsListed) {
  const auto mesh = beam();
  const Problem problem(mesh, {}, ProblemSettings{});
  const std::vector<std::string> skipped = problem.skipped();
  EXPECT_NE(std::find(skipped.begin(), skipped.end(), "gravity load (gravity is zero)"), skipped.end());
  EXPECT_TRUE(problem.loads()->empty());
  EXPECT_FALSE(problem.dynamicSystem().externalForce);
}

}  // namespace
}  // namespace asyncfem
