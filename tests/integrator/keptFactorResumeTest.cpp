// SPDX-License-Identifier: BSD-3-Clause
// Backward Euler's kept factor (reuseFactor) through internalState(): a run continued from
// (u, v, t) and the internal state taken at any step equals the uninterrupted run bit for
// bit, with no refactorization at the point it was taken (a checkpoint's frame start).
#include <gtest/gtest.h>

#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <functional>
#include <limits>
#include <memory>
#include <string>

#include "testSystems.hpp"

namespace asyncfem::test {
namespace {

// The rubber cantilever bent well out of the linear range (tip at 40% of its length).
Eigen::VectorXd largeBend(const TetMesh& mesh) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int vertex = 0; vertex < mesh.numVertices(); ++vertex) {
    const double x = mesh.restPosition(vertex).x();
    u[(3 * vertex) + 2] = 0.4 * x * x;
  }
  return u;
}

// A 0.2 cube of 2^3 cells (rubber) 0.01 above the ground y = 0, implicit penalty
// contact (with normal damping or without), sliding along x at 0.8 m/s as it falls and lands.
struct GroundDrop {
  GroundDrop(ForceModelType forceModel, double damping) {
    BoxMeshSpec spec;
    spec.origin = Eigen::Vector3d(0.0, 0.01, 0.0);
    spec.size = Eigen::Vector3d::Constant(0.2);
    spec.cells = Eigen::Vector3i::Constant(2);
    spec.material = Material{"rubber", 1000.0, 1e5, 0.4};
    auto mesh = std::make_shared<const TetMesh>(makeBoxMesh(spec));
    ProblemSettings settings;
    settings.forceModel = forceModel;
    settings.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
    settings.implicitContact = true;
    PenaltyContactParameters contact;
    contact.stiffness = 1e5;
    contact.damping = damping;
    auto penalty = std::make_shared<const PenaltyContact>(
        mesh->restPositions(), std::vector<ContactPlane>{ContactPlane{}}, std::vector<ContactSphere>{}, contact);
    problem = std::make_shared<const Problem>(mesh, std::vector<int>{}, settings, std::vector<VertexLoad>{}, penalty);
    system = problem->dynamicSystem();
    velocity = Eigen::VectorXd::Zero(system.numDofs());
    for (Eigen::Index i = 0; i < velocity.size(); i += 3) velocity[i] = 0.8;
  }
  std::shared_ptr<const Problem> problem;
  DynamicSystem system;
  Eigen::VectorXd velocity;
};

struct Case {
  std::string name;
  std::function<DynamicSystem()> system;
  Eigen::VectorXd u0, v0;
  double h = 0.0;
  IntegratorOptions options;
  int steps = 0;
};

bool bitIdentical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::equal(a.data(), a.data() + a.size(), b.data());
}

// What the resumes covered.
struct Coverage {
  int keptAcross = 0;   ///< restored states whose kept factor the next step used without refactoring
  int withContact = 0;  ///< states whose kept factor's matrix had contact blocks
};

// Runs c.steps steps, taking the state after each step k; for every k a second
// integrator restored from it runs the remaining steps and must end bit for bit where the
// first did.
Coverage expectEveryResumeBitIdentical(const Case& c) {
  SCOPED_TRACE(c.name);
  BackwardEuler whole(c.system(), c.h, c.options);
  whole.setState(c.u0, c.v0);
  struct Taken {
    Eigen::VectorXd u, v, internal;
    double t;
  };
  std::vector<Taken> taken;
  for (int k = 0; k < c.steps; ++k) {
    whole.step();
    taken.push_back({whole.displacement(), whole.velocity(), whole.internalState(), whole.time()});
  }
  EXPECT_NE(whole.factorReuseStats(), nullptr);
  if (whole.factorReuseStats() != nullptr) {
    EXPECT_GT(whole.factorReuseStats()->pcgIterations, 0) << "the run never reused its factor";
    EXPECT_LT(whole.factorReuseStats()->refactorizations, c.steps);
  }
  Coverage coverage;
  for (int k = 0; k + 1 < c.steps; ++k) {
    // Entry 12 of the state is its count of contact blocks (detail/keptFactor.cpp's layout).
    if (taken[k].internal.size() > 12 && taken[k].internal[12] > 0.0) ++coverage.withContact;
    BackwardEuler resumed(c.system(), c.h, c.options);
    resumed.setState(taken[k].u, taken[k].v, taken[k].t);
    resumed.setInternalState(taken[k].internal);
    const long long rebuilt = resumed.stats().factorizations;  // the kept factor, factored again
    resumed.step();
    if (rebuilt == 1 && resumed.stats().factorizations == 1) ++coverage.keptAcross;
    for (int j = k + 1; j + 1 < c.steps; ++j) resumed.step();
    EXPECT_TRUE(bitIdentical(resumed.displacement(), whole.displacement())) << "resumed after step " << k + 1;
    EXPECT_TRUE(bitIdentical(resumed.velocity(), whole.velocity())) << "resumed after step " << k + 1;
    EXPECT_TRUE(bitIdentical(resumed.internalState(), whole.internalState())) << "resumed after step " << k + 1;
    EXPECT_TRUE(resumed.report().resumeCaveat.empty()) << resumed.report().resumeCaveat;
  }
  return coverage;
}

Case bentBar(const std::string& name, const IntegratorOptions& options, double alpha = 0.0, double beta = 0.0) {
  auto bar = std::make_shared<BarBody>(makeBar(MassType::consistent, alpha, beta, Eigen::Vector3i(8, 2, 2)));
  Case c;
  c.name = name;
  c.system = [bar, alpha, beta] {
    return withSettings(*bar->problem, testSettings(ForceModelType::corotational, alpha, beta)).dynamicSystem();
  };
  c.u0 = largeBend(bar->mesh);
  c.v0 = Eigen::VectorXd::Zero(c.u0.size());
  c.h = 2e-3;
  c.options = options;
  c.steps = 24;
  return c;
}

TEST(KeptFactorResume, LinearizedStepsContinueBitForBitWithoutRefactoring) {
  IntegratorOptions options;  // the default path: linearized steps, kept factor in single precision
  EXPECT_GT(expectEveryResumeBitIdentical(bentBar("linearized", options)).keptAcross, 5);
  options.pcgSinglePrecision = false;
  EXPECT_GT(expectEveryResumeBitIdentical(bentBar("double factor", options)).keptAcross, 5);
}

TEST(KeptFactorResume, NewtonIterationsContinueBitForBit) {
  IntegratorOptions options;
  options.maxIterations = 3;  // line search on, D at the step start
  EXPECT_GT(expectEveryResumeBitIdentical(bentBar("newton", options, 0.5, 2e-4)).keptAcross, 0);
  options.rayleighStiffnessAtIterate = true;  // J's damping term at the iterate
  EXPECT_GT(expectEveryResumeBitIdentical(bentBar("newton, damping at the iterate", options, 0.5, 2e-4)).keptAcross, 0);
}

TEST(KeptFactorResume, ImplicitContactBlocksGoWithTheKeptFactor) {
  // A linear model (the kept factor serves the contact steps' matrices), the linearized
  // corotational step (contact iterations on the step-start tangent) and Newton with the
  // contact of each iterate (the settings of implicitContactTest's cases).
  struct Setting {
    std::string name;
    ForceModelType model;
    double damping;
    int maxIterations;
  };
  for (const Setting& setting : {Setting{"linear", ForceModelType::linear, 20.0, 1},
                                 Setting{"corotational, linearized", ForceModelType::corotational, 0.0, 1},
                                 Setting{"corotational, newton", ForceModelType::corotational, 20.0, 20}}) {
    const auto drop = std::make_shared<GroundDrop>(setting.model, setting.damping);
    Case c;
    c.name = setting.name;
    c.system = [drop] { return drop->system; };
    c.u0 = Eigen::VectorXd::Zero(drop->system.numDofs());
    c.v0 = drop->velocity;
    c.h = 1.0 / 120.0;
    c.options.contactLowRank = false;  // a linear model's contact steps on the kept factor
    c.options.maxIterations = setting.maxIterations;
    c.options.tolerance = setting.maxIterations > 1 ? 1e-10 : c.options.tolerance;
    c.steps = 30;
    const Coverage coverage = expectEveryResumeBitIdentical(c);
    EXPECT_GT(coverage.withContact, 0) << setting.name;
    EXPECT_GT(coverage.keptAcross, 0) << setting.name;
  }
}

TEST(KeptFactorResume, WithoutTheStateTheResumeRefactorsAndSaysSo) {
  // An empty state (a checkpoint written before the kept factor was in checkpoints):
  // the first step factors afresh, and the report's resume caveat says the run is not
  // bit-identical; the result is within the PCG tolerance's reach, not equal.
  const Case c = bentBar("empty state", IntegratorOptions{});
  BackwardEuler whole(c.system(), c.h, c.options);
  whole.setState(c.u0, c.v0);
  for (int k = 0; k < 6; ++k) whole.step();
  BackwardEuler resumed(c.system(), c.h, c.options);
  resumed.setState(whole.displacement(), whole.velocity(), whole.time());
  resumed.setInternalState(Eigen::VectorXd());
  for (int k = 0; k < 6; ++k) {
    whole.step();
    resumed.step();
  }
  EXPECT_NE(resumed.report().resumeCaveat.find("no kept-factor state"), std::string::npos)
      << resumed.report().resumeCaveat;
  EXPECT_LT(scaledDifference(resumed.displacement(), whole.displacement()), 1e-6);
}

TEST(KeptFactorResume, ForeignStatesAreRefused) {
  const Case c = bentBar("refused", IntegratorOptions{});
  BackwardEuler source(c.system(), c.h, c.options);
  source.setState(c.u0, c.v0);
  for (int k = 0; k < 3; ++k) source.step();
  const Eigen::VectorXd good = source.internalState();
  ASSERT_GT(good.size(), 13);
  BackwardEuler target(c.system(), c.h, c.options);
  EXPECT_NO_THROW(target.setInternalState(good));
  Eigen::VectorXd bad = good;
  bad[0] = 2.0;  // another layout version
  EXPECT_THROW(target.setInternalState(bad), Error);
  bad = good.head(good.size() - 1);
  EXPECT_THROW(target.setInternalState(bad), Error);
  bad = good;
  bad[bad.size() - 1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(target.setInternalState(bad), Error);
  bad = good;
  bad[1] = 0.5;  // a flag that is no flag
  EXPECT_THROW(target.setInternalState(bad), Error);
  // Without a kept factor (exact solves) there is no state, and none is taken.
  IntegratorOptions exact;
  exact.reuseFactor = false;
  BackwardEuler plain(c.system(), c.h, exact);
  EXPECT_EQ(plain.internalState().size(), 0);
  EXPECT_THROW(plain.setInternalState(good), Error);
}

}  // namespace
}  // namespace asyncfem::test
