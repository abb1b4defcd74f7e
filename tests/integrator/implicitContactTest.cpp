// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <memory>
#include <string>

// Penalty contact treated implicitly by backward Euler (DynamicSystem::externalForceJacobian).
namespace asyncfem::test {
namespace {

constexpr double kGroundStiffness = 1e5;  // per vertex: omega h about 10 at h = 1/60 (vertex mass ~0.3)

// A free 0.2 cube of 2 x 2 x 2 cells (27 vertices, rubber E = 1e5, density 1000) whose
// bottom face is `gap` above the ground y = 0, under gravity.
struct DroppedCube {
  DroppedCube(ForceModelType forceModel, bool implicit, const PenaltyContactParameters& contact, double gap,
              std::vector<ContactSphere> spheres = {}, int cells = 2)
      : spheres(spheres) {
    BoxMeshSpec spec;
    spec.origin = Eigen::Vector3d(0.0, gap, 0.0);
    spec.size = Eigen::Vector3d::Constant(0.2);
    spec.cells = Eigen::Vector3i::Constant(cells);
    spec.material = Material{"rubber", 1000.0, 1e5, 0.4};
    mesh = std::make_shared<const TetMesh>(makeBoxMesh(spec));
    ProblemSettings settings;
    settings.forceModel = forceModel;
    settings.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
    settings.implicitContact = implicit;
    // The ground y = 0, or the spheres alone when there are some.
    std::vector<ContactPlane> planes;
    if (spheres.empty()) planes.push_back(ContactPlane{});
    auto penalty = std::make_shared<const PenaltyContact>(mesh->restPositions(), planes, spheres, contact);
    problem = std::make_shared<const Problem>(mesh, std::vector<int>{}, settings, std::vector<VertexLoad>{}, penalty);
    system = problem->dynamicSystem();
  }

  // Total energy: kinetic, elastic (linear: 1/2 u^T K u), gravity's and the contact springs'.
  double energy(const Eigen::VectorXd& u, const Eigen::VectorXd& v) const {
    const Eigen::SparseMatrix<double>& K = problem->stiffnessMatrix();
    const Eigen::SparseMatrix<double>& M = problem->massMatrix();
    double e = (0.5 * v.dot(M * v)) + (0.5 * u.dot(K * u));
    const Eigen::Matrix3Xd& rest = mesh->restPositions();
    Eigen::VectorXd weight = Eigen::VectorXd::Zero(u.size());
    for (Eigen::Index i = 1; i < u.size(); i += 3) weight[i] = 9.81;
    e += (M * weight).dot(u);  // m g y, up to a constant
    for (int vtx = 0; vtx < mesh->numVertices(); ++vtx) {
      const Eigen::Vector3d x = rest.col(vtx) + u.segment<3>(3 * vtx);
      if (spheres.empty()) {
        const double depth = -x.y();
        if (depth > 0.0) e += 0.5 * kGroundStiffness * depth * depth;
      }
      for (const ContactSphere& sphere : spheres) {
        const double depth = sphere.radius - (x - sphere.center).norm();
        if (depth > 0.0) e += 0.5 * kGroundStiffness * depth * depth;
      }
    }
    return e;
  }

  std::vector<ContactSphere> spheres;
  std::shared_ptr<const TetMesh> mesh;
  std::shared_ptr<const Problem> problem;
  DynamicSystem system;
};

PenaltyContactParameters frictionless() {
  PenaltyContactParameters p;
  p.stiffness = kGroundStiffness;
  return p;
}

// R = M dv - h (f_ext(t1, u1, v1) - f_int(u1)) at the end state of one step of a linear,
// undamped model, relative to |h f_ext|: the backward Euler equations with the contact force
// at the end state. For a frictionless plane the force is affine in u while the contact set
// holds, so the implicit step solves them exactly: tolerance 1e-9 (direct solves of a
// system with condition number ~1e6).
double endStateResidual(const DroppedCube& cube, const Eigen::VectorXd& u0, const Eigen::VectorXd& v0,
                        const Eigen::VectorXd& u1, const Eigen::VectorXd& v1, double h) {
  Eigen::VectorXd force = Eigen::VectorXd::Zero(u0.size());
  cube.system.externalForce(h, u1, v1, force);
  const Eigen::VectorXd residual =
      (cube.problem->massMatrix() * (v1 - v0)) - (h * (force - (cube.problem->stiffnessMatrix() * u1)));
  return residual.norm() / (h * force.norm());
}

TEST(ImplicitContact, PlaneStepSolvesTheEquationsWithTheForceAtItsEndState) {
  const double h = 1.0 / 60.0;
  IntegratorOptions options;
  options.reuseFactor = false;
  double residual[2] = {0.0, 0.0};
  for (const bool implicit : {true, false}) {
    DroppedCube cube(ForceModelType::linear, implicit, frictionless(), 0.01);
    const int n = cube.system.numDofs();
    // Falling at 1.5 m/s: the prediction and the end state both have the bottom face in contact.
    Eigen::VectorXd v0 = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 1; i < n; i += 3) v0[i] = -1.5;
    const Eigen::VectorXd u0 = Eigen::VectorXd::Zero(n);
    BackwardEuler integrator(cube.system, h, options);
    integrator.setState(u0, v0);
    integrator.step();
    const Eigen::VectorXd& u1 = integrator.displacement();
    EXPECT_GT(cube.problem->contact()->activeContacts(u1), 0);
    residual[implicit ? 0 : 1] = endStateResidual(cube, u0, v0, u1, integrator.velocity(), h);
  }
  EXPECT_LT(residual[0], 1e-9);
  // The explicit step misses the spring entirely (the vertices start 0.01 above the ground).
  EXPECT_GT(residual[1], 1e-2);
}

// Dropped from 0.05 onto a spring with omega h about 10: the explicit force gains energy at
// the impact (it pushes the vertex out from the depth it reached), the implicit one never:
// every step's total energy at most the initial one (allowance 1e-9 of the drop's 3.9 J
// of potential energy, for rounding in the sums), and the cube ends at rest on the ground, its deepest
// vertex within 1 mm (weight over stiffness is 0.03 mm per vertex).
TEST(ImplicitContact, StiffGroundDissipatesWhereExplicitContactGainsEnergy) {
  const double h = 1.0 / 60.0;
  double largest[2] = {0.0, 0.0};
  double initial = 0.0;
  double finalDepth = 0.0;
  for (const bool implicit : {true, false}) {
    DroppedCube cube(ForceModelType::linear, implicit, frictionless(), 0.05);
    const int n = cube.system.numDofs();
    BackwardEuler integrator(cube.system, h);
    integrator.setState(Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n));
    initial = cube.energy(integrator.displacement(), integrator.velocity());
    double worst = initial;
    for (int k = 0; k < 120; ++k) {
      integrator.step();
      worst = std::max(worst, cube.energy(integrator.displacement(), integrator.velocity()));
    }
    largest[implicit ? 0 : 1] = worst;
    if (implicit) finalDepth = cube.problem->contact()->maxPenetration(integrator.displacement());
  }
  const double drop = 8.0 * 9.81 * 0.05;  // m g h of the 8 kg cube
  EXPECT_LE(largest[0], initial + (1e-9 * drop));
  EXPECT_GT(largest[1], initial + (0.1 * drop));
  EXPECT_LT(finalDepth, 1e-3);
}

// A sphere obstacle under one corner of the cube (its normal turns with the vertex: the
// negative curvature term of its derivatives is dropped by the projection onto the
// symmetric positive semi-definite part): at omega h about 10 the implicit run never gains
// energy (the same 1e-9 allowance as above) and the cube slides off the sphere, whose
// deepest penetration stays below 5 mm (the weight on a few vertices over k).
TEST(ImplicitContact, SphereObstacleNeverGainsEnergy) {
  const double h = 1.0 / 60.0;
  const ContactSphere sphere{Eigen::Vector3d(0.05, -0.2, 0.05), 0.2};  // top at y = 0, under a corner
  DroppedCube cube(ForceModelType::linear, true, frictionless(), 0.02, {sphere});
  const int n = cube.system.numDofs();
  BackwardEuler integrator(cube.system, h);
  integrator.setState(Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n));
  const double initial = cube.energy(integrator.displacement(), integrator.velocity());
  const double drop = 8.0 * 9.81 * 0.02;
  double worst = initial, deepest = 0.0;
  int contactSteps = 0;
  for (int k = 0; k < 60; ++k) {
    integrator.step();
    worst = std::max(worst, cube.energy(integrator.displacement(), integrator.velocity()));
    const double depth = cube.problem->contact()->maxPenetration(integrator.displacement());
    deepest = std::max(deepest, depth);
    if (depth > 0.0) ++contactSteps;
  }
  EXPECT_GT(contactSteps, 3);
  EXPECT_LE(worst, initial + (1e-9 * drop));
  EXPECT_LT(deepest, 5e-3);
}

// The kept-factor path (reuseFactor: PCG on the contact steps' matrices, preconditioned by
// an earlier factor) against a factorization per contact step, over a bounce with normal
// damping while sliding: the same trajectory to 1e-7 of the largest displacement (PCG to a relative
// residual of 1e-10, condition number ~1e6, over 60 steps).
TEST(ImplicitContact, KeptFactorMatchesAFactorizationPerContactStep) {
  const double h = 1.0 / 120.0;
  PenaltyContactParameters contact = frictionless();
  contact.damping = 20.0;
  Eigen::VectorXd end[2];
  for (const bool reuse : {true, false}) {
    DroppedCube cube(ForceModelType::linear, true, contact, 0.01);
    const int n = cube.system.numDofs();
    IntegratorOptions options;
    options.reuseFactor = reuse;
    options.contactLowRank = false;  // the contact step's own matrix (the test below has the update)
    BackwardEuler integrator(cube.system, h, options);
    Eigen::VectorXd v0 = Eigen::VectorXd::Zero(n);
    for (Eigen::Index i = 0; i < n; i += 3) v0[i] = 0.8;  // sliding along x as it lands
    integrator.setState(Eigen::VectorXd::Zero(n), v0);
    for (int k = 0; k < 60; ++k) integrator.step();
    end[reuse ? 0 : 1] = integrator.displacement();
    if (!reuse) {
      EXPECT_GT(integrator.stats().factorizations, 10);
    }
  }
  EXPECT_LT((end[0] - end[1]).norm(), 1e-7 * end[1].cwiseAbs().maxCoeff());
}

// A linear model's contact steps by a low-rank update of its contact-free factor
// (contactLowRank, Woodbury) against the same steps with their own factorization, on a cube
// of 6 x 6 x 6 cells landing on its 49-vertex bottom face, with normal damping, and on a
// sphere under a corner: the same trajectory to 1e-9 of the largest displacement (both
// exact solves; Woodbury's error grows with the condition of I + U^T A^{-1} U, here below
// 1e4), and the update was taken (its count in the run report).
TEST(ImplicitContact, LowRankUpdateMatchesTheFactorization) {
  const double h = 1.0 / 120.0;
  PenaltyContactParameters contact = frictionless();
  contact.damping = 20.0;
  const ContactSphere sphere{Eigen::Vector3d(0.02, -0.3, 0.02), 0.3};
  for (const std::vector<ContactSphere>& spheres : {std::vector<ContactSphere>{}, std::vector<ContactSphere>{sphere}}) {
    Eigen::VectorXd end[2];
    for (const bool lowRank : {true, false}) {
      DroppedCube cube(ForceModelType::linear, true, contact, 0.005, spheres, 6);
      const int n = cube.system.numDofs();
      IntegratorOptions options;
      options.reuseFactor = false;
      options.contactLowRank = lowRank;
      BackwardEuler integrator(cube.system, h, options);
      Eigen::VectorXd v0 = Eigen::VectorXd::Zero(n);
      for (Eigen::Index i = 1; i < n; i += 3) v0[i] = -1.0;
      integrator.setState(Eigen::VectorXd::Zero(n), v0);
      for (int k = 0; k < 20; ++k) integrator.step();
      end[lowRank ? 0 : 1] = integrator.displacement();
      const std::string line = integrator.report().lines.at(0);
      const bool updated = line.find("; 0 contact solves by a low-rank update") == std::string::npos;
      EXPECT_EQ(updated, lowRank) << line;
    }
    EXPECT_LT((end[0] - end[1]).norm(), 1e-9 * end[1].cwiseAbs().maxCoeff()) << spheres.size() << " spheres";
  }
}

// Newton iterations evaluate the contact at each iterate (a corotational cube spinning so
// that a corner lands first, with clamped normal damping): a step converges to 1e-10 unless
// its solution sits on a kink of the contact force (a vertex at the clamp), where the
// iteration may stop at contactIterations; such steps are counted, and stay within 1e-2 of
// the step's impulse. A contact force frozen at the prediction would leave every contact
// step's residual at the size of the force's change over the step (about 1e-1 here).
TEST(ImplicitContact, NewtonIterationsConvergeWithTheContactOfTheIterate) {
  const double h = 1.0 / 60.0;
  PenaltyContactParameters contact = frictionless();
  contact.damping = 20.0;
  DroppedCube cube(ForceModelType::corotational, true, contact, 0.005);
  const int n = cube.system.numDofs();
  IntegratorOptions options;
  options.maxIterations = 20;
  options.tolerance = 1e-10;
  BackwardEuler integrator(cube.system, h, options);
  Eigen::VectorXd v0 = Eigen::VectorXd::Zero(n);
  for (int vtx = 0; vtx < cube.mesh->numVertices(); ++vtx) {
    const Eigen::Vector3d x = cube.mesh->restPositions().col(vtx);
    // Falling at 1 m/s, spinning about z at 3 rad/s, sliding at 0.5 m/s.
    v0.segment<3>(3 * vtx) = Eigen::Vector3d(0.5 - (3.0 * (x.y() - 0.1)), -1.0 + (3.0 * (x.x() - 0.1)), 0.0);
  }
  integrator.setState(Eigen::VectorXd::Zero(n), v0);
  int contactSteps = 0, converged = 0;
  for (int k = 0; k < 20; ++k) {
    integrator.step();
    if (cube.problem->contact()->activeContacts(integrator.displacement()) > 0) ++contactSteps;
    if (integrator.lastRelativeResidual() <= 1e-10) ++converged;
    EXPECT_LE(integrator.lastRelativeResidual(), 1e-2) << "step " << k;
  }
  EXPECT_EQ(contactSteps, 20);
  EXPECT_GE(converged, 18);
  const RunReport report = integrator.report();
  ASSERT_FALSE(report.lines.empty());
  EXPECT_NE(report.lines[0].find(std::to_string(20 - converged) + " steps stopped at 20 iterations unconverged"),
            std::string::npos)
      << report.lines[0];
  EXPECT_TRUE(std::find(integrator.stats().skipped.begin(), integrator.stats().skipped.end(),
                        "line search (implicit contact: the step equations are no potential's gradient; Newton "
                        "updates taken in full)") != integrator.stats().skipped.end());
}

// The linearized step of a nonlinear model (maxIterations = 1) keeps its elastic force
// linearized at the step start and iterates the contact only: every step converges to the
// default tolerance 1e-8 (or involves no contact: residual not evaluated, -1), some take
// more than one solve, and the corotational cube comes to rest on the ground at omega h about
// 10 (deepest vertex below 1 mm, speed below 1 mm/s after 2 s).
TEST(ImplicitContact, LinearizedNonlinearStepIteratesTheContactOnly) {
  const double h = 1.0 / 60.0;
  DroppedCube cube(ForceModelType::corotational, true, frictionless(), 0.05);
  const int n = cube.system.numDofs();
  BackwardEuler integrator(cube.system, h);
  integrator.setState(Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n));
  int iterated = 0;
  for (int k = 0; k < 120; ++k) {
    integrator.step();
    EXPECT_LE(integrator.lastRelativeResidual(), 1e-8) << "step " << k;
    if (integrator.lastIterations() > 1) ++iterated;
  }
  EXPECT_GT(iterated, 0);
  EXPECT_LT(cube.problem->contact()->maxPenetration(integrator.displacement()), 1e-3);
  EXPECT_LT(integrator.velocity().cwiseAbs().maxCoeff(), 1e-3);
}

// Friction is not treated implicitly: a problem that asks for it with implicit contact is
// refused, naming the friction.
TEST(ImplicitContact, FrictionIsRefused) {
  PenaltyContactParameters contact = frictionless();
  contact.friction = 0.3;
  try {
    DroppedCube cube(ForceModelType::linear, true, contact, 0.01);
    ADD_FAILURE() << "implicit contact with friction accepted";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("implicit contact with friction 0.3"), std::string::npos) << error.what();
  }
  EXPECT_NO_THROW(DroppedCube(ForceModelType::linear, false, contact, 0.01));
}

// An integrator that applies the force explicitly refuses a system that asks for implicit
// contact, naming the scene key, instead of running a spring it cannot keep stable.
TEST(ImplicitContact, ExplicitIntegratorsRefuseIt) {
  DroppedCube cube(ForceModelType::linear, true, frictionless(), 0.01);
  IntegratorRegistry registry;
  registerSingleRateIntegrators(registry);
  for (const std::string name : {"central-differences", "symplectic-euler", "trapezoidal"}) {
    IntegratorContext context;
    context.mesh = cube.mesh;
    context.system = cube.system;
    context.timestep = 1e-3;
    context.hasContact = true;
    context.sourceName = "drop.json";
    try {
      (void)registry.create(name, context, nlohmann::json::object());
      ADD_FAILURE() << name << " accepted implicit contact";
    } catch (const ValidationError& error) {
      EXPECT_NE(std::string(error.what()).find("drop.json: contact.implicit: integrator \"" + name + "\""),
                std::string::npos)
          << error.what();
    }
  }
  IntegratorContext context;
  context.mesh = cube.mesh;
  context.system = cube.system;
  context.timestep = 1e-3;
  context.hasContact = true;
  EXPECT_NO_THROW((void)registry.create("backward-euler", context, nlohmann::json::object()));
}

}  // namespace
}  // namespace asyncfem::test
