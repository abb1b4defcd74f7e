// SPDX-License-Identifier: BSD-3-Clause
// Implicit penalty contact in the asynchronous step (docs/asynchronous-integrator.md,
// "Implicit contact"): the step against its per-substep definition with the contact force
// at each substep's state, the energy of a stiff impact, the single-rate identity with every
// contact in L, regions whose springs are stiff or soft at their own step, and a failing force.
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "asyncTestSystem.hpp"
#include "definitionStep.hpp"
#include "nestedDefinition.hpp"

namespace asyncfem {
namespace {

using test::relativeDifference;

constexpr double kLargeStep = 2e-3;
constexpr double kGap = 5e-4;  // the ground y = -kGap, below the bar's bottom face y = 0

// The stiff-end bar (clamped at x = 0) above the ground, its tip falling at 0.5 m/s. The
// penalty stiffness gives omega hL = omegaHL for the median lumped mass of the tip's
// bottom-face vertices (what lands first). With load: the bar's pull on its x = 1 face.
struct ContactBar {
  ContactBar(double omegaHL, bool implicit, bool load = true) : ts(test::makeTestSystem(0.0, 0.0)) {
    if (!load) ts.system.externalForce = nullptr;
    const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.75);
    std::vector<double> masses;
    const Eigen::VectorXd lumped = ts.system.mass * Eigen::VectorXd::Ones(ts.system.numDofs());
    for (int v : tip) {
      if (ts.mesh.restPosition(v).y() < 1e-9) masses.push_back(lumped[3 * v]);
      ts.v0[3 * v + 1] -= 0.5;
    }
    std::nth_element(masses.begin(), masses.begin() + static_cast<std::ptrdiff_t>(masses.size() / 2), masses.end());
    const double omega = omegaHL / kLargeStep;
    stiffness = omega * omega * masses[masses.size() / 2];
    PenaltyContactParameters parameters;
    parameters.stiffness = stiffness;
    penalty = std::make_shared<const PenaltyContact>(ts.mesh.restPositions(),
                                                     std::vector<ContactPlane>{{Eigen::Vector3d::UnitY(), -kGap}},
                                                     std::vector<ContactSphere>{}, parameters);
    ExternalForceFunction pull = ts.system.externalForce;
    std::shared_ptr<const PenaltyContact> contact = penalty;
    ts.system.externalForce = [pull, contact](double t, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                              Eigen::VectorXd& f) {
      if (pull) pull(t, u, v, f);
      contact->addForces(u, v, f);
    };
    if (implicit) {
      ts.system.externalForceJacobian = [contact](double, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                                  VertexJacobian& jacobian) { jacobian = contact->jacobian(u, v); };
    }
  }

  // Kinetic + elastic + the contact springs' energy (no load).
  double energy(const Integrator& integrator) const {
    const Eigen::VectorXd& u = integrator.displacement();
    double springs = 0.0;
    for (int v = 0; v < ts.mesh.numVertices(); ++v) {
      const double depth = -kGap - (ts.mesh.restPosition(v).y() + u[3 * v + 1]);
      if (depth > 0.0) springs += 0.5 * stiffness * depth * depth;
    }
    return integrator.mechanicalEnergy() + springs;
  }

  test::TestSystem ts;
  std::shared_ptr<const PenaltyContact> penalty;
  double stiffness = 0.0;
};

AsyncOptions tightContact() {
  AsyncOptions options;
  options.contact.tolerance = 1e-13;
  options.contact.iterations = 200;
  return options;
}

// How many of `vertices` are in contact at u.
int inContact(const ContactBar& bar, const Eigen::VectorXd& u, const std::vector<int>& vertices) {
  const std::vector<int> touching = bar.penalty->verticesWithin(u, 0.0);
  return static_cast<int>(std::count_if(vertices.begin(), vertices.end(), [&](int v) {
    return std::binary_search(touching.begin(), touching.end(), v);
  }));
}

// The structured solve with implicit contact equals the per-substep definition with the
// contact force at each fast substep's own state and at L's end state, solved by Newton
// (DefinitionStep), over three steps in which fast and L vertices touch the ground
// (omega hL = 4 for the tip: 0.5 at hS = hL / 8, 2 at hL / 2), with the set-up's factors
// and with the quick set-up (conjugate gradients to 1e-10 for L's system). Tolerance 1e-8:
// the contact iterations stop at a relative residual of 1e-13 and the definition's Newton
// at round-off; both solve systems of condition ~1e6. Explicit contact misses it by far
// more (so the check can fail).
TEST(AsyncImplicitContact, StepMatchesThePerSubstepDefinition) {
  for (const int ratio : {8, 2}) {
    for (const bool implicit : {true, false}) {
      const ContactBar bar(4.0, implicit);
      const std::vector<int> tip = test::verticesBeyond(bar.ts.mesh, 0.75);
      const std::vector<AsyncRegion> regions{{"tip", tip, ratio}};
      std::vector<int> large;
      for (int v = 0; v < bar.ts.mesh.numVertices(); ++v)
        if (!std::binary_search(tip.begin(), tip.end(), v)) large.push_back(v);
      AsyncBackwardEuler async(bar.ts.system, kLargeStep, regions, tightContact());
      // The quick set-up's path too (L's system by conjugate gradients on the whole
      // system's factor, with the contact blocks in its operator).
      AsyncOptions quickOptions = tightContact();
      quickOptions.keptFactors.quickSetUp = true;
      AsyncBackwardEuler quick(bar.ts.system, kLargeStep, regions, quickOptions);
      async.setState(bar.ts.u0, bar.ts.v0);
      quick.setState(bar.ts.u0, bar.ts.v0);
      const test::DefinitionStep definition(bar.ts.mesh, bar.ts.system, regions);
      Eigen::VectorXd u = bar.ts.u0, v = bar.ts.v0;
      double worst = 0.0, worstQuick = 0.0;
      int fastTouching = 0, largeTouching = 0;
      for (int k = 0; k < 3; ++k) {
        async.step();
        quick.step();
        definition.step(kLargeStep, k * kLargeStep, u, v);
        worst = std::max({worst, relativeDifference(async.displacement(), u), relativeDifference(async.velocity(), v)});
        worstQuick = std::max(
            {worstQuick, relativeDifference(quick.displacement(), u), relativeDifference(quick.velocity(), v)});
        fastTouching = std::max(fastTouching, inContact(bar, u, tip));
        largeTouching = std::max(largeTouching, inContact(bar, u, large));
      }
      EXPECT_GT(fastTouching, 0);
      EXPECT_GT(largeTouching, 0);
      if (implicit) {
        EXPECT_LT(worst, 1e-8) << "ratio " << ratio;
        EXPECT_LT(worstQuick, 1e-8) << "ratio " << ratio << ", quick set-up";
        // The region's touching vertices take their blocks into A^S (checked here too).
        EXPECT_GT(async.runStats().contactRegionFactorizations, 0) << "ratio " << ratio;
        EXPECT_NE(async.report().lines.back().find("async implicit contact"), std::string::npos);
      } else {
        EXPECT_GT(worst, 1e-3);
        EXPECT_GT(worstQuick, 1e-3);
      }
    }
  }
}

// The hierarchy solve ("method": "hierarchy") with implicit contact (Eqs. N13-N14) on the
// same two-level partition equals the same per-substep definition: Newton on the whole step
// system with the contact blocks at each DOF's own step state. Tolerance 1e-8 as above.
TEST(AsyncImplicitContact, HierarchySolveMatchesThePerSubstepDefinition) {
  const ContactBar bar(4.0, true);
  const std::vector<int> tip = test::verticesBeyond(bar.ts.mesh, 0.75);
  const std::vector<AsyncRegion> regions{{"tip", tip, 8}};
  AsyncOptions options = tightContact();
  options.method = AsyncSolveMethod::hierarchy;
  AsyncBackwardEuler async(bar.ts.system, kLargeStep, regions, options);
  ASSERT_EQ(async.stepSolver(), AsyncStepSolver::hierarchy);
  async.setState(bar.ts.u0, bar.ts.v0);
  const test::DefinitionStep definition(bar.ts.mesh, bar.ts.system, regions);
  Eigen::VectorXd u = bar.ts.u0, v = bar.ts.v0;
  double worst = 0.0;
  int fastTouching = 0;
  for (int k = 0; k < 3; ++k) {
    async.step();
    definition.step(kLargeStep, k * kLargeStep, u, v);
    worst = std::max({worst, relativeDifference(async.displacement(), u), relativeDifference(async.velocity(), v)});
    fastTouching = std::max(fastTouching, inContact(bar, u, tip));
  }
  std::printf("hierarchy solve with implicit contact, two levels: %.3e from the per-substep definition\n", worst);
  EXPECT_GT(fastTouching, 0);
  EXPECT_LT(worst, 1e-8);
  EXPECT_EQ(async.runStats().contactSteps, 3);
  EXPECT_GT(async.runStats().contactIterations, 3);  // Newton took solves beyond the first
  EXPECT_EQ(async.runStats().unconvergedContactSteps, 0);
}

// Nested regions (a tip at 8 inside an end at 2) with implicit contact: every step's
// solution satisfies Eq. N3 with the load of each DOF's step taken at the state of that
// step's end (Eq. N13), evaluated directly from the definition (nestedDefinitionResidual),
// to 1e-9 of the largest term (the contact iterations stop at 1e-13 of the step's scale;
// the sums in the definition add round-off of systems of condition ~1e6). With explicit
// contact (the load at the step's start state) the same residual is far larger once the
// bar touches, so the check can fail.
TEST(AsyncImplicitContact, NestedRegionsSolveTheirDefinitionWithContact) {
  for (const bool implicit : {true, false}) {
    const ContactBar bar(4.0, implicit);
    const std::vector<int> tip = test::verticesBeyond(bar.ts.mesh, 0.875);
    std::vector<int> end;
    for (const int v : test::verticesBeyond(bar.ts.mesh, 0.5))
      if (!std::binary_search(tip.begin(), tip.end(), v)) end.push_back(v);
    AsyncBackwardEuler async(bar.ts.system, kLargeStep, {{"end", end, 2}, {"tip", tip, 8}}, tightContact());
    ASSERT_EQ(async.stepSolver(), AsyncStepSolver::hierarchy);
    EXPECT_EQ(async.partition().levels(), (std::vector<int>{1, 2, 8}));
    async.setState(bar.ts.u0, bar.ts.v0);
    double worst = 0.0;
    int tipTouching = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::VectorXd u0 = async.displacement(), v0 = async.velocity();
      async.step();
      worst = std::max(worst, test::nestedDefinitionResidual(bar.ts, async, u0, v0, kLargeStep, k * kLargeStep, true));
      tipTouching = std::max(tipTouching, inContact(bar, async.displacement(), tip));
    }
    std::printf("nested regions, %s contact: largest residual of Eq. N3 with N13's loads %.3e\n",
                implicit ? "implicit" : "explicit", worst);
    EXPECT_GT(tipTouching, 0);
    if (implicit) {
      EXPECT_LT(worst, 1e-9);
      EXPECT_EQ(async.runStats().contactSteps, 4);
      EXPECT_EQ(async.runStats().unconvergedContactSteps, 0);
      EXPECT_GT(async.runStats().contactStepSystemFactorizations, 0);
      bool reported = false;
      for (const std::string& line : async.report().lines)
        reported = reported || line.find("Newton on the step system") != std::string::npos;
      EXPECT_TRUE(reported);
    } else {
      EXPECT_GT(worst, 1e-4);
      EXPECT_EQ(async.runStats().contactSteps, 0);
    }
  }
}

// An undamped impact on a ground stiff for hL (omega hL = 8, 0.5 at hS = hL / 16): with
// implicit contact the energy (kinetic, elastic and the springs') never increases from one
// large step to the next (allowance 1e-9 of the initial energy for the contact iterations'
// tolerance and round-off), through the landing and the rebound. Explicit contact at the
// step's start state gains (more than 1% of it), so the check can fail.
TEST(AsyncImplicitContact, StiffImpactNeverGainsEnergy) {
  for (const bool implicit : {true, false}) {
    const ContactBar bar(8.0, implicit, false);
    const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(bar.ts.mesh, 0.75), 16}};
    AsyncBackwardEuler async(bar.ts.system, kLargeStep, regions, tightContact());
    async.setState(bar.ts.u0, bar.ts.v0);
    const double initial = bar.energy(async);
    double energy = initial, worstGain = 0.0;
    int touched = 0;
    for (int k = 0; k < 60; ++k) {
      async.step();
      const double next = bar.energy(async);
      worstGain = std::max(worstGain, next - energy);
      energy = next;
      touched = std::max(touched, bar.penalty->activeContacts(async.displacement()));
    }
    EXPECT_GT(touched, 0);
    if (implicit) {
      EXPECT_LE(worstGain, 1e-9 * initial);
    } else {
      EXPECT_GT(worstGain, 1e-2 * initial);
    }
  }
}

// With no fast region every contact is L's: the step is single-rate backward Euler with the
// contact at the end state, which BackwardEuler solves by Newton. Both to 1e-13, compared to
// 1e-8 (two different solves of systems with condition ~1e6) over 20 steps of landing.
TEST(AsyncImplicitContact, WithoutRegionsItIsSingleRateImplicitContact) {
  const ContactBar bar(8.0, true);
  AsyncBackwardEuler async(bar.ts.system, kLargeStep, {}, tightContact());
  IntegratorOptions options;
  options.tolerance = 1e-13;
  options.contactIterations = 50;
  BackwardEuler single(bar.ts.system, kLargeStep, options);
  async.setState(bar.ts.u0, bar.ts.v0);
  single.setState(bar.ts.u0, bar.ts.v0);
  double worst = 0.0;
  int touched = 0;
  for (int k = 0; k < 20; ++k) {
    async.step();
    single.step();
    worst = std::max(worst, relativeDifference(async.displacement(), single.displacement()));
    touched = std::max(touched, bar.penalty->activeContacts(async.displacement()));
  }
  EXPECT_GT(touched, 0);
  EXPECT_LT(worst, 1e-8);
  // The blocks kept between steps are not in a checkpoint: the summary says what a resumed
  // run then matches.
  EXPECT_NE(async.report().resumeCaveat.find("implicit contact"), std::string::npos) << async.report().resumeCaveat;
}

// A region's vertices in contact take their blocks into A^S (refactored, counted in the
// summary), whether their springs are stiff at hS (ratio 1: omega hS = 8) or not (ratio 16:
// 0.5), and every step converges to the tolerance within contactIterations: where a
// vertex's contact starts or ends within the step the block is exact for some substeps
// only, and the mixing (Eq. C5) makes up the rest (without it, at ratio 16, steps stopped
// unconverged at 5e-4).
TEST(AsyncImplicitContact, RegionsInContactTakeTheirBlocksAndConverge) {
  const ContactBar bar(8.0, true, false);
  for (const int ratio : {1, 16}) {
    const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(bar.ts.mesh, 0.75), ratio}};
    AsyncBackwardEuler async(bar.ts.system, kLargeStep, regions);
    async.setState(bar.ts.u0, bar.ts.v0);
    for (int k = 0; k < 20; ++k) async.step();
    const AsyncRunStats& stats = async.runStats();
    EXPECT_EQ(stats.contactSteps, 20);
    EXPECT_TRUE(async.displacement().allFinite());
    EXPECT_GT(stats.contactRegionFactorizations, 0) << "ratio " << ratio;
    EXPECT_EQ(stats.unconvergedContactSteps, 0) << "ratio " << ratio;
    EXPECT_LT(stats.contactIterations, 20 * AsyncOptions{}.contact.iterations) << "ratio " << ratio;
    bool reported = false;
    for (const std::string& line : async.report().lines)
      reported = reported || line.find("0 steps stopped at 30 iterations unconverged") != std::string::npos;
    EXPECT_TRUE(reported);
  }
}

// A failing contact iteration is an error naming the step, the vertex and its region, and
// nothing of the step is committed: here the contact force turns NaN at the third step.
TEST(AsyncImplicitContact, NonFiniteForceIsAnErrorNamingTheVertex) {
  ContactBar bar(4.0, true, false);
  const ExternalForceFunction contact = bar.ts.system.externalForce;
  bar.ts.system.externalForce = [contact](double t, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                          Eigen::VectorXd& f) {
    contact(t, u, v, f);
    if (t > 5e-3) f[3 * 40 + 1] = std::nan("");
  };
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(bar.ts.mesh, 0.75), 8}};
  AsyncBackwardEuler async(bar.ts.system, kLargeStep, regions);
  async.setState(bar.ts.u0, bar.ts.v0);
  async.step();
  async.step();
  const Eigen::VectorXd before = async.displacement();
  try {
    async.step();
    ADD_FAILURE() << "a non-finite contact force was accepted";
  } catch (const NumericalError& error) {
    EXPECT_NE(std::string(error.what()).find("is not finite at vertex 40 (implicit contact)"), std::string::npos)
        << error.what();
  }
  EXPECT_EQ(async.displacement(), before);
}

}  // namespace
}  // namespace asyncfem
