// SPDX-License-Identifier: BSD-3-Clause
// The Schroeder et al. 2011 comparator (docs/asynchronous-integrator.md, (S1)-(S7)): its
// single-rate limits, rigid motions, momentum, the force distributing projection and the
// explicit stability limit of its outer layer.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/asyncIntegrator/schroeder2011.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/problem/problem.hpp>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../common/testProblems.hpp"

namespace asyncfem {
namespace {

// system with its mass matrix lumped to row sums, as Schroeder2011 uses it (S1): the
// single-rate integrator that Schroeder2011 reduces to.
DynamicSystem lumped(DynamicSystem system) {
  const Eigen::VectorXd rowSums = system.mass * Eigen::VectorXd::Ones(system.numDofs());
  system.mass = Eigen::SparseMatrix<double>(rowSums.asDiagonal());
  return system;
}

double relativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).norm() / std::max({1e-300, a.norm(), b.norm()});
}

// The stiff-end bar (clamped at x = 0, stiff light end x > 0.75 = the outer layer) with a
// time-varying pull on its free face and a random initial state.
struct Bar : test::TestBody {
  using TestBody::TestBody;
  Eigen::VectorXd u0, v0;
  std::vector<int> stiffVertices;
};

Bar makeBar(double alpha, double beta) {
  Bar bar(test::stiffEndBarProblem(test::testSettings(ForceModelType::linear, alpha, beta)));
  const std::vector<int> pulled = bar.mesh.vertexSet("xmax");
  bar.system.externalForce = [pulled](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (const int v : pulled) f[3 * v + 1] -= 0.5 * std::cos(40.0 * t);
  };
  test::RandomState state = test::randomState(bar.system.freeDofs, 11, test::FixedDofDraws::skipped);
  bar.u0 = std::move(state.displacement);
  bar.v0 = std::move(state.velocity);
  bar.stiffVertices = bar.mesh.vertexSet("stiff");
  return bar;
}

// A free-floating rubber bar (nothing fixed), 8 x 2 x 2 cubes; the outer layer is x > 0.74.
test::TestBody floatingBar(double alpha, double beta) {
  std::shared_ptr<const TetMesh> mesh = test::rubberBarMesh(Eigen::Vector3i(8, 2, 2));
  return test::TestBody(Problem(mesh, {}, test::testSettings(ForceModelType::linear, alpha, beta)));
}

std::vector<int> verticesBeyond(const TetMesh& mesh, double xMin) {
  std::vector<int> out;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).x() >= xMin) out.push_back(v);
  return out;
}

// The smallest ratio whose substeps are stable at hL, with a margin of one.
int stableRatio(const DynamicSystem& system, const std::vector<int>& vertices, double hL) {
  Schroeder2011Options probe;
  probe.force = true;
  const Schroeder2011 integrator(system, hL, {{"outer", vertices, 1}}, probe);
  return static_cast<int>(std::ceil(hL / integrator.largestStableSubstep(0))) + 1;
}

Eigen::VectorXd momentum(const DynamicSystem& system, const Eigen::VectorXd& v) {
  const Eigen::VectorXd p = system.mass * v;
  Eigen::VectorXd total = Eigen::VectorXd::Zero(3);
  for (Eigen::Index k = 0; k < p.size(); ++k) total[k % 3] += p[k];
  return total;
}

TEST(Schroeder2011, RatioOneIsBackwardEulerAtTheLargeStep) {
  // m = 1: no explicit substep, (S6) is (A1) at hL with the lumped mass (S1). 1e-9
  // relative: the same equations factored by LU (compound) and by Cholesky (backward
  // Euler), over 5 steps.
  for (const auto& [alpha, beta] : {std::pair{0.0, 0.0}, std::pair{0.3, 2e-3}}) {
    for (const double rigidity : {0.0, 1.0}) {
      Bar bar = makeBar(alpha, beta);
      const double hL = 4e-3;
      Schroeder2011Options options;
      options.rigidity = rigidity;
      Schroeder2011 schroeder(bar.system, hL, {{"stiff", bar.stiffVertices, 1}}, options);
      BackwardEuler single(lumped(bar.system), hL);
      schroeder.setState(bar.u0, bar.v0);
      single.setState(bar.u0, bar.v0);
      for (int s = 0; s < 5; ++s) {
        schroeder.step();
        single.step();
      }
      EXPECT_LT(relativeDifference(schroeder.displacement(), single.displacement()), 1e-9) << alpha << " " << beta;
      EXPECT_LT(relativeDifference(schroeder.velocity(), single.velocity()), 1e-9) << alpha << " " << beta;
      // The bar's consistent M became its row sums, exactly.
      const Eigen::MatrixXd mass(schroeder.system().mass), expected(lumped(bar.system).mass);
      EXPECT_EQ((mass - expected).cwiseAbs().maxCoeff(), 0.0);
      EXPECT_EQ(schroeder.report().lines.size(), 1U);
    }
  }
}

TEST(Schroeder2011, NoOuterLayerIsBackwardEulerAtTheLargeStep) {
  // No fast region: the whole body is the implicit interior (1e-9, as above).
  Bar bar = makeBar(0.3, 2e-3);
  const double hL = 4e-3;
  Schroeder2011 schroeder(bar.system, hL, {});
  BackwardEuler single(lumped(bar.system), hL);
  schroeder.setState(bar.u0, bar.v0);
  single.setState(bar.u0, bar.v0);
  for (int s = 0; s < 5; ++s) {
    schroeder.step();
    single.step();
  }
  EXPECT_LT(relativeDifference(schroeder.displacement(), single.displacement()), 1e-9);
  EXPECT_LT(relativeDifference(schroeder.velocity(), single.velocity()), 1e-9);
  EXPECT_EQ(schroeder.name(), "schroeder2011");
  EXPECT_TRUE(std::isinf(schroeder.stableTimestepEstimate()));
}

TEST(Schroeder2011, SubstepsChangeTheResult) {
  // The ratio-1 identity is not vacuous: with m > 1 the outer layer's substeps (S3) differ
  // from backward Euler at hL by far more than round-off (> 1e-4 relative after 5 steps).
  Bar bar = makeBar(0.0, 1e-3);
  const double hL = 4e-3;
  const int m = stableRatio(bar.system, bar.stiffVertices, hL);
  ASSERT_GT(m, 1);
  Schroeder2011 schroeder(bar.system, hL, {{"stiff", bar.stiffVertices, m}});
  BackwardEuler single(lumped(bar.system), hL);
  schroeder.setState(bar.u0, bar.v0);
  single.setState(bar.u0, bar.v0);
  for (int s = 0; s < 5; ++s) {
    schroeder.step();
    single.step();
  }
  EXPECT_GT(relativeDifference(schroeder.velocity(), single.velocity()), 1e-4);
  EXPECT_LT(schroeder.displacement().lpNorm<Eigen::Infinity>(), 1.0);
}

TEST(Schroeder2011, RigidMotionsStayRigid) {
  // A rigid displacement (translation plus an infinitesimal rotation field) and a rigid
  // velocity (translation plus rotation) produce no elastic force in the substeps, no
  // boundary impulse to filter and none in the coupled solve: the body keeps moving
  // rigidly. alpha = 0 (mass damping would slow rigid motion); beta K v = 0 for rigid v.
  // 1e-11 relative: round-off of K applied to a rigid field (K r ~ 1e-16 |K| |r|) over
  // 10 steps, amplified by the solves' conditioning.
  for (const double rigidity : {0.0, 1.0}) {
    test::TestBody body = floatingBar(0.0, 2e-3);
    const std::vector<int> outer = verticesBeyond(body.mesh, 0.74);
    const double hL = 5e-3;
    const int m = stableRatio(body.system, outer, hL);
    Schroeder2011Options options;
    options.rigidity = rigidity;
    Schroeder2011 schroeder(body.system, hL, {{"outer", outer, m}}, options);
    const Eigen::Vector3d translation(0.3, -0.2, 0.1), omega(0.5, -1.0, 2.0), shift(1e-3, 2e-3, -1e-3),
        tilt(1e-3, -2e-3, 3e-3);
    Eigen::VectorXd u0(body.system.numDofs()), v0(body.system.numDofs());
    for (int v = 0; v < body.mesh.numVertices(); ++v) {
      const Eigen::Vector3d x = body.mesh.restPosition(v);
      u0.segment<3>(3 * v) = shift + tilt.cross(x);
      v0.segment<3>(3 * v) = translation + omega.cross(x);
    }
    schroeder.setState(u0, v0);
    const int steps = 10;
    for (int s = 0; s < steps; ++s) schroeder.step();
    EXPECT_LT(relativeDifference(schroeder.velocity(), v0), 1e-11) << rigidity;
    const Eigen::VectorXd expected = u0 + (steps * hL) * v0;
    EXPECT_LT(relativeDifference(schroeder.displacement(), expected), 1e-11) << rigidity;
  }
}

TEST(Schroeder2011, ConservesLinearMomentum) {
  // (S4): with alpha = 0, nothing fixed and no external force, every impulse of (S3) and
  // (S6) is a sum of element forces (K_e and beta K_e annihilate translations) and the
  // projection (S5) keeps the net impulse: total linear momentum is conserved. 1e-12
  // relative to sum |M v| (round-off of the sparse products over 20 steps). Angular
  // momentum is not conserved, as by single-rate backward Euler with linear FEM (its
  // forces are not rotation-invariant).
  for (const double rigidity : {0.0, 0.5, 1.0}) {
    test::TestBody body = floatingBar(0.0, 2e-3);
    const std::vector<int> outer = verticesBeyond(body.mesh, 0.74);
    const double hL = 5e-3;
    const int m = stableRatio(body.system, outer, hL);
    Schroeder2011Options options;
    options.rigidity = rigidity;
    Schroeder2011 schroeder(body.system, hL, {{"outer", outer, m}}, options);
    test::RandomState state = test::randomState(body.system.freeDofs, 3, test::FixedDofDraws::skipped);
    schroeder.setState(state.displacement, state.velocity);
    const Eigen::VectorXd before = momentum(body.system, state.velocity);
    const double scale = (body.system.mass * state.velocity).cwiseAbs().sum();
    for (int s = 0; s < 20; ++s) schroeder.step();
    const Eigen::VectorXd after = momentum(body.system, schroeder.velocity());
    EXPECT_LT((after - before).norm(), 1e-12 * scale) << rigidity;
    // Not trivially: the motion changed the velocities by much more.
    EXPECT_GT((schroeder.velocity() - state.velocity).norm(), 1e-3 * state.velocity.norm());
  }
  // The wrong variant fails: with mass damping alpha > 0 momentum decays (> 1e-3 relative).
  test::TestBody damped = floatingBar(2.0, 2e-3);
  const std::vector<int> outer = verticesBeyond(damped.mesh, 0.74);
  Schroeder2011 schroeder(damped.system, 5e-3, {{"outer", outer, stableRatio(damped.system, outer, 5e-3)}});
  Eigen::VectorXd v0(damped.system.numDofs());
  for (int v = 0; v < damped.mesh.numVertices(); ++v) v0.segment<3>(3 * v) = Eigen::Vector3d(0.1, 0.0, 0.0);
  schroeder.setState(Eigen::VectorXd::Zero(v0.size()), v0);
  for (int s = 0; s < 20; ++s) schroeder.step();
  const Eigen::VectorXd before = momentum(damped.system, v0);
  EXPECT_GT((momentum(damped.system, schroeder.velocity()) - before).norm(), 1e-3 * before.norm());
}

TEST(Schroeder2011, ProjectionKeepsNetForceAndTorqueAndRemovesTheRest) {
  // (S5) on a random set of DOFs of a deformed bar. 1e-12 relative: dense 6 x 6 algebra.
  test::TestBody body = floatingBar(0.0, 0.0);
  const int n = body.mesh.numVertices();
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd positions(3 * n), mass(3 * n), impulse = Eigen::VectorXd::Zero(3 * n);
  for (int v = 0; v < n; ++v) positions.segment<3>(3 * v) = body.mesh.restPosition(v);
  for (Eigen::Index k = 0; k < positions.size(); ++k) {
    positions[k] += 0.01 * uniform(random);
    mass[k] = 1.0 + 0.5 * uniform(random);
  }
  std::vector<int> dofs;
  for (int dof = 0; dof < 3 * n; ++dof)
    if (positions[dof - dof % 3] < 0.6) dofs.push_back(dof);
  for (const int dof : dofs) impulse[dof] = uniform(random);
  const RigidImpulseProjection projection(positions, mass, dofs);
  auto netForceAndTorque = [&](const Eigen::VectorXd& j) {
    Eigen::VectorXd out = Eigen::VectorXd::Zero(6);
    for (const int dof : dofs) {
      const Eigen::Vector3d x = positions.segment<3>(3 * (dof / 3));
      const Eigen::Vector3d f = Eigen::Vector3d::Unit(dof % 3) * j[dof];
      out.head<3>() += f;
      out.tail<3>() += x.cross(f);
    }
    return out;
  };
  const Eigen::VectorXd projected = projection.apply(impulse);
  const Eigen::VectorXd net = netForceAndTorque(impulse);
  EXPECT_LT((netForceAndTorque(projected) - net).norm(), 1e-12 * net.norm());
  // Idempotent: a rigid-acceleration impulse m (a + alpha x r) is kept.
  EXPECT_LT((projection.apply(projected) - projected).norm(), 1e-12 * projected.norm());
  // The remainder has zero net force and torque, and is removed.
  const Eigen::VectorXd remainder = impulse - projected;
  EXPECT_LT(netForceAndTorque(remainder).norm(), 1e-12 * net.norm());
  EXPECT_LT(projection.apply(remainder).norm(), 1e-12 * remainder.norm());
  EXPECT_GT(remainder.norm(), 0.1 * impulse.norm());  // not vacuous
  // The elastic force of a rigid displacement of the set (K r = 0 up to round-off) is zero
  // after filtering, and rigidity 0 leaves any impulse unchanged.
  EXPECT_LT((projection.apply(impulse, 0.0) - impulse).norm(), 1e-15 * impulse.norm());
  const Eigen::VectorXd half = projection.apply(impulse, 0.5);
  EXPECT_LT((half - 0.5 * (impulse + projected)).norm(), 1e-12 * impulse.norm());
}

TEST(Schroeder2011, UnstableSubstepIsRejectedNamingTheRegionAndTheLimit) {
  // (S7): a substep above the outer layer's limit is a TimestepError that names the
  // region and the largest stable substep; at a ratio that meets the limit it runs.
  // beta = 1e-5 s: implicit damping raises the limit to at least 2 beta (S7), which a
  // beta of 1e-3 s would make larger than hL / 2 here.
  Bar bar = makeBar(0.0, 1e-5);
  const double hL = 4e-3;
  Schroeder2011Options forced;
  forced.force = true;
  const Schroeder2011 probe(bar.system, hL, {{"stiff", bar.stiffVertices, 2}}, forced);
  const double limit = probe.largestStableSubstep(0);
  ASSERT_GT(hL / 2, limit);  // ratio 2 is unstable on this bar
  try {
    Schroeder2011 unstable(bar.system, hL, {{"stiff", bar.stiffVertices, 2}});
    FAIL() << "no error";
  } catch (const TimestepError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("fast region S_1 'stiff'"), std::string::npos) << message;
    std::ostringstream number;
    number.precision(6);
    number << limit << " s, the largest stable substep";
    EXPECT_NE(message.find(number.str()), std::string::npos) << message;
  }
  // The limit is the true one within the estimate's margin: at 1.05 x the limit the
  // stable ratio runs 100 steps with bounded energy; at twice the limit (forced) the
  // outer layer blows up within 100 steps (energy x 1e6).
  auto finalEnergy = [&](int ratio) {
    Schroeder2011 integrator(bar.system, hL, {{"stiff", bar.stiffVertices, ratio}}, forced);
    integrator.setState(bar.u0, bar.v0);
    try {
      for (int s = 0; s < 100; ++s) integrator.step();
    } catch (const NumericalError&) {
      return std::numeric_limits<double>::infinity();
    }
    return integrator.mechanicalEnergy();
  };
  Schroeder2011 initial(bar.system, hL, {{"stiff", bar.stiffVertices, 1}});
  initial.setState(bar.u0, bar.v0);
  const double energy0 = initial.mechanicalEnergy();
  const int stable = static_cast<int>(std::ceil(1.05 * hL / limit));
  const int unstable = std::max(1, static_cast<int>(std::floor(0.5 * hL / limit)));
  EXPECT_LT(finalEnergy(stable), 10.0 * energy0);
  EXPECT_GT(finalEnergy(unstable), 1e6 * energy0);
  EXPECT_NO_THROW(Schroeder2011(bar.system, hL, {{"stiff", bar.stiffVertices, stable}}));
  EXPECT_NEAR(Schroeder2011(bar.system, hL, {{"stiff", bar.stiffVertices, stable}}).stableTimestepEstimate(),
              stable * limit, 1e-12 * stable * limit);
}

TEST(Schroeder2011, RegistryBuildsItFromAsyncRegionsAndNamesTheTimestepKey) {
  Bar bar = makeBar(0.0, 1e-5);
  IntegratorRegistry registry;
  registerMultirateIntegrators(registry);
  auto context = [&]() {
    IntegratorContext c;
    c.mesh = bar.problem->sharedMesh();
    c.system = bar.system;
    c.timestep = 4e-3;
    c.sourceName = "test.json";
    return c;
  };
  const nlohmann::json good = {{"regions", {{{"name", "stiff"}, {"ratio", 60}, {"vertexSets", {"stiff"}}}}},
                               {"rigidity", 0.5}};
  const std::unique_ptr<Integrator> integrator = registry.create("schroeder2011", context(), good);
  EXPECT_EQ(integrator->name(), "schroeder2011");
  EXPECT_EQ(dynamic_cast<const Schroeder2011&>(*integrator).options().rigidity, 0.5);
  nlohmann::json bad = good;
  bad["regions"][0]["ratio"] = 2;
  try {
    registry.create("schroeder2011", context(), bad);
    FAIL() << "no error";
  } catch (const TimestepError& error) {
    EXPECT_EQ(std::string(error.what()).rfind("test.json: integrator.timestep: schroeder2011: fast region S_1", 0), 0U)
        << error.what();
  }
  nlohmann::json foreign = good;
  foreign["coupling"] = "stable";
  EXPECT_THROW(registry.create("schroeder2011", context(), foreign), ValidationError);
  nlohmann::json outOfRange = good;
  outOfRange["rigidity"] = 2.0;
  EXPECT_THROW(registry.create("schroeder2011", context(), outOfRange), ValidationError);
}

}  // namespace
}  // namespace asyncfem
