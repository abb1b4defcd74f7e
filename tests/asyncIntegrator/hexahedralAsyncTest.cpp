// SPDX-License-Identifier: BSD-3-Clause
// The asynchronous integrator on a hexahedral mesh (docs/asynchronous-integrator.md,
// "Hexahedral meshes"): the two-level step against its per-substep definition, the nested
// step against Eq. N3, the energy theorem, the element tangents of the hexahedral force
// models, nonlinear models at small amplitude, the comparators at m = 1, run-time regions,
// the loads policy and the element frequencies of the region proposal.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/asyncIntegrator/loadsPolicy.hpp>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/asyncIntegrator/runTimeRegions.hpp>
#include <asyncfem/asyncIntegrator/schroeder2011.hpp>
#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>
#include <vector>

#include "../hexElements/hexBar.hpp"
#include "asyncTestSystem.hpp"
#include "definitionStep.hpp"
#include "nestedDefinition.hpp"

namespace asyncfem {
namespace {

using test::relativeDifference;

/// hexBar(2) ([0, 1] x [0, 0.25] x [0, 0.25], 8 x 2 x 2 cubes) with the materials of the
/// tetrahedral stiffEndBarProblem: soft (density 1000, E = 1e5, nu = 0.4), and stiff and
/// light (200, 5e6, 0.3) for the cubes beyond x = 0.75.
std::shared_ptr<const TetMesh> stiffEndHexBar() {
  const TetMesh bar = test::hexBar(2);
  std::vector<int> materials(static_cast<std::size_t>(bar.numElements()), 0);
  for (int e = 0; e < bar.numElements(); ++e)
    if (bar.hexahedronRestPositions(e).row(0).mean() > 0.75) materials[static_cast<std::size_t>(e)] = 1;
  return std::make_shared<const TetMesh>(
      bar.restPositions(), bar.hexahedra(),
      std::vector<Material>{Material{"soft", 1000.0, 1e5, 0.4}, Material{"stiff", 200.0, 5e6, 0.3}}, materials);
}

/// The hexahedral bar clamped at x = 0 and pulled at x = 1 as makeTestSystem() pulls the
/// tetrahedral one (f_y = -0.5 cos(40 t), f_z = 0.2 sin(25 t) N per vertex), from a random
/// state scaled by amplitude.
test::TestSystem hexTestSystem(const ProblemSettings& settings, double amplitude = 1.0) {
  std::shared_ptr<const TetMesh> mesh = stiffEndHexBar();
  std::vector<int> clamped = test::verticesOnPlanes(*mesh, {0.0});
  test::TestSystem ts{test::TestBody(Problem(mesh, std::move(clamped), settings)), {}, {}};
  const std::vector<int> pulled = test::verticesOnPlanes(ts.mesh, {1.0});
  ts.system.externalForce = [pulled](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (int v : pulled) {
      f[3 * v + 1] += -0.5 * std::cos(40.0 * t);
      f[3 * v + 2] += 0.2 * std::sin(25.0 * t);
    }
  };
  test::RandomState state = test::randomState(ts.system.freeDofs, 7, test::FixedDofDraws::drawnThenZeroed);
  ts.u0 = amplitude * state.displacement;
  ts.v0 = amplitude * state.velocity;
  return ts;
}

/// The last layer of cubes (x >= 0.875: 4 hexahedra, 18 vertices) at ratio m.
std::vector<AsyncRegion> tipRegion(const TetMesh& mesh, int m) {
  return {{"tip", test::verticesBeyond(mesh, 0.875), m}};
}

/// The larger relative difference of the displacements and of the velocities of a and b
/// after `steps` large steps, both from the state of ts.
double stepsApart(Integrator& a, Integrator& b, const test::TestSystem& ts, int steps) {
  for (Integrator* integrator : {&a, &b}) {
    integrator->setState(ts.u0, ts.v0);
    for (int k = 0; k < steps; ++k) integrator->step();
  }
  return std::max(relativeDifference(a.displacement(), b.displacement()),
                  relativeDifference(a.velocity(), b.velocity()));
}

// The two-level structured solve on hexahedra equals the stable coupling's per-substep
// definition solved densely from the hexahedral K and M (interface stiffness summed from
// hexLinearStiffness), with and without damping, at m = 2 and 3, under a time-varying load.
// Tolerance 1e-9 as on tetrahedra: two factorizations of systems with condition numbers
// ~1e6. The definition at another ratio (m + 1) must differ by more than 1e-6, or the
// comparison could not tell ratios apart.
TEST(HexahedralAsync, TwoLevelStepMatchesTheDefinition) {
  for (const double alpha : {0.0, 0.3}) {
    const test::TestSystem ts = hexTestSystem(test::testSettings(ForceModelType::linear, alpha, alpha * 5e-3));
    for (const int m : {2, 3}) {
      const std::vector<AsyncRegion> regions = tipRegion(ts.mesh, m);
      AsyncBackwardEuler async(ts.mesh, ts.system, 2e-3, regions, test::withCoupling(AsyncCoupling::stable));
      async.setState(ts.u0, ts.v0);
      const test::DefinitionStep definition(ts.mesh, ts.system, regions);
      Eigen::VectorXd u = ts.u0, v = ts.v0;
      double worst = 0.0;
      for (int k = 0; k < 2; ++k) {
        async.step();
        definition.step(2e-3, k * 2e-3, u, v);
        worst = std::max({worst, relativeDifference(async.displacement(), u), relativeDifference(async.velocity(), v)});
      }
      EXPECT_LT(worst, 1e-9) << "alpha " << alpha << ", m " << m;
      std::vector<AsyncRegion> otherRatio = tipRegion(ts.mesh, m + 1);
      Eigen::VectorXd uOther = ts.u0, vOther = ts.v0;
      test::DefinitionStep(ts.mesh, ts.system, otherRatio).step(2e-3, 0.0, uOther, vOther);
      test::DefinitionStep(ts.mesh, ts.system, otherRatio).step(2e-3, 2e-3, uOther, vOther);
      const double other = relativeDifference(async.velocity(), vOther);
      EXPECT_GT(other, 1e-6) << "alpha " << alpha << ", m " << m;
      std::printf("hexahedra, alpha %.1f, m %d: async vs definition %.2e, vs the definition at m %d %.2e\n", alpha, m,
                  worst, m + 1, other);
    }
  }
}

// The nested (hierarchy) step system on hexahedra against Eq. N3 evaluated from its
// solution: two levels inside one another (8 inside 2), damped, loaded. Round-off in the
// sums: 1e-10 of the largest term, as on tetrahedra.
TEST(HexahedralAsync, NestedStepSolvesTheDefinition) {
  const test::TestSystem ts = hexTestSystem(test::testSettings(ForceModelType::linear, 0.4, 1e-3));
  std::vector<AsyncRegion> regions{{"outer", {}, 2}, {"inner", test::verticesBeyond(ts.mesh, 0.875), 8}};
  for (int v : test::verticesBeyond(ts.mesh, 0.5))
    if (ts.mesh.restPosition(v).x() < 0.875 - 1e-12) regions[0].vertices.push_back(v);
  AsyncBackwardEuler nested(ts.mesh, ts.system, 4e-3, regions, AsyncOptions{});
  EXPECT_TRUE(nested.partition().touching());
  nested.setState(ts.u0, ts.v0);
  nested.step();
  const double first = test::nestedDefinitionResidual(ts, nested, ts.u0, ts.v0, 4e-3, 0.0);
  EXPECT_LT(first, 1e-10);
  const Eigen::VectorXd u1 = nested.displacement(), v1 = nested.velocity();
  nested.step();
  const double second = test::nestedDefinitionResidual(ts, nested, u1, v1, 4e-3, 4e-3);
  EXPECT_LT(second, 1e-10);
  // The residual of the second step evaluated from the wrong start state must be large.
  EXPECT_GT(test::nestedDefinitionResidual(ts, nested, ts.u0, ts.v0, 4e-3, 4e-3), 1e-6);
  std::printf("hexahedra, nested 2 and 8: Eq. N3 residual %.2e, %.2e\n", first, second);
}

// One region solved by the hierarchy solve equals the two-level stable coupling (both are
// the same step; different factorizations): 1e-9 relative.
TEST(HexahedralAsync, HierarchyOfOneRegionIsTheTwoLevelStep) {
  const test::TestSystem ts = hexTestSystem(test::testSettings(ForceModelType::linear, 0.2, 1e-3));
  const std::vector<AsyncRegion> regions = tipRegion(ts.mesh, 3);
  AsyncBackwardEuler twoLevel(ts.mesh, ts.system, 4e-3, regions, test::withCoupling(AsyncCoupling::stable));
  AsyncOptions hierarchy;
  hierarchy.method = AsyncSolveMethod::hierarchy;
  AsyncBackwardEuler nested(ts.mesh, ts.system, 4e-3, regions, hierarchy);
  EXPECT_LT(stepsApart(twoLevel, nested, ts, 3), 1e-9);
}

// Energy theorem on hexahedra: a free, undamped linear run with the stable coupling never
// gains energy from one large step to the next, consistent and lumped mass, m = 2, 3, 16,
// two-level and hierarchy solves. Tolerance 1e-12 relative: the energy's round-off.
TEST(HexahedralAsync, StableCouplingNeverGainsEnergy) {
  for (const MassType mass : {MassType::consistent, MassType::lumped}) {
    test::TestSystem ts = hexTestSystem(test::testSettings(ForceModelType::linear, 0.0, 0.0, mass));
    ts.system.externalForce = nullptr;
    for (const int m : {2, 3, 16}) {
      for (const AsyncSolveMethod method : {AsyncSolveMethod::structured, AsyncSolveMethod::hierarchy}) {
        AsyncOptions options = test::withCoupling(AsyncCoupling::stable);
        options.method = method;
        AsyncBackwardEuler async(ts.mesh, ts.system, 2e-3, tipRegion(ts.mesh, m), options);
        async.setState(ts.u0, ts.v0);
        double energy = async.mechanicalEnergy(), worst = -1.0;
        for (int k = 0; k < 30; ++k) {
          async.step();
          const double next = async.mechanicalEnergy();
          worst = std::max(worst, next / energy - 1.0);
          energy = next;
        }
        EXPECT_LE(worst, 1e-12) << (mass == MassType::lumped ? "lumped" : "consistent") << ", m " << m;
        EXPECT_LT(worst, 0.0) << "the run dissipates nothing: the check would pass for any integrator";
      }
    }
  }
}

// The hexahedral force models' element tangents (ForceModel::elementTangentOfAnyKind, what
// the stable coupling's interface elements and the hierarchy solve read on hexahedra) sum
// to the model's assembled tangent at a deformed state. 1e-12 relative: the same element
// matrices summed in another order. The state is far enough from rest that the tangent
// differs from the rest one by more than 1e-6 (else a rest tangent would pass too).
TEST(HexahedralAsync, ElementTangentsSumToTheModelTangent) {
  for (const ForceModelType type : {ForceModelType::corotational, ForceModelType::stvk, ForceModelType::neoHookean}) {
    const test::TestSystem ts = hexTestSystem(test::testSettings(type), 30.0);
    ForceModel& model = *ts.system.forceModel;
    Eigen::SparseMatrix<double> stiffness = model.createStiffnessMatrix();
    model.tangentStiffness(ts.u0, stiffness);
    const Eigen::MatrixXd assembled(stiffness);
    model.tangentStiffness(Eigen::VectorXd::Zero(ts.mesh.numDofs()), stiffness);
    const Eigen::MatrixXd rest(stiffness);
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(ts.mesh.numDofs(), ts.mesh.numDofs());
    for (int e = 0; e < ts.mesh.numElements(); ++e) {
      Eigen::MatrixXd tangent;
      ASSERT_TRUE(model.elementTangentOfAnyKind(ts.u0, e, tangent)) << toString(type);
      ASSERT_EQ(tangent.rows(), 24);
      for (int p = 0; p < 24; ++p)
        for (int q = 0; q < 24; ++q)
          sum(3 * ts.mesh.elementVertex(e, p / 3) + p % 3, 3 * ts.mesh.elementVertex(e, q / 3) + q % 3) +=
              tangent(p, q);
    }
    const double scale = assembled.cwiseAbs().maxCoeff();
    EXPECT_LT((sum - assembled).cwiseAbs().maxCoeff() / scale, 1e-12) << toString(type);
    EXPECT_GT((rest - assembled).cwiseAbs().maxCoeff() / scale, 1e-6) << toString(type);
  }
}

// The comparators run on hexahedra: at m = 1 multirate-uncoupled is backward Euler at hL
// and schroeder2011 backward Euler at hL with the mass lumped to row sums (1e-9 relative:
// the same equations under other factorizations, 5 steps); at m = 3 both differ from it by
// more than 1e-6 (schroeder2011's explicit substeps are beyond their stability limit there:
// only the difference is checked).
TEST(HexahedralAsync, ComparatorsAtRatioOneAreBackwardEuler) {
  const test::TestSystem ts = hexTestSystem(test::testSettings(ForceModelType::linear, 0.3, 2e-3));
  DynamicSystem lumped = ts.system;
  lumped.mass = Eigen::SparseMatrix<double>(
      Eigen::VectorXd(ts.system.mass * Eigen::VectorXd::Ones(ts.mesh.numDofs())).asDiagonal());
  for (const int m : {1, 3}) {
    BackwardEuler single(ts.system, 4e-3), singleLumped(lumped, 4e-3);
    UncoupledMultirate uncoupled(ts.system, 4e-3, tipRegion(ts.mesh, m));
    Schroeder2011 schroeder(ts.system, 4e-3, tipRegion(ts.mesh, m));
    const double uncoupledApart = stepsApart(uncoupled, single, ts, 5);
    const double schroederApart = stepsApart(schroeder, singleLumped, ts, 5);
    if (m == 1) {
      EXPECT_LT(uncoupledApart, 1e-9);
      EXPECT_LT(schroederApart, 1e-9);
    } else {
      EXPECT_GT(uncoupledApart, 1e-6);
      EXPECT_GT(schroederApart, 1e-6);
    }
  }
}

// Run-time regions on hexahedra: a scheduled window open over the whole run is the fixed
// region, bit for bit (the same set-up, then the same steps); the error indicator grows a
// region by the hexahedra's vertices and the run goes on. The loads policy's lumped vertex
// masses sum to the bar's mass, 0.0625 (0.75 x 1000 + 0.25 x 200) kg, to round-off (1e-12).
TEST(HexahedralAsync, RunTimeRegionsAndVertexMasses) {
  const test::TestSystem ts = hexTestSystem(test::testSettings(ForceModelType::linear, 0.0, 1e-3));
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.75);
  AsyncBackwardEuler fixed(ts.mesh, ts.system, 5e-3, {{"tip", tip, 4}});
  AsyncBackwardEuler scheduled(ts.mesh, ts.system, 5e-3, {});
  RunTimeRegionOptions window;
  window.schedule = {{"tip", 0.0, 1.0, tip, 4}};
  scheduled.setRunTimeRegions(window);
  EXPECT_EQ(stepsApart(fixed, scheduled, ts, 5), 0.0);
  ASSERT_EQ(scheduled.repartitions().size(), 1U);
  EXPECT_EQ(scheduled.repartitions()[0].fastVertices, static_cast<int>(tip.size()));
  RunTimeRegionOptions indicator;
  indicator.indicator = true;
  AsyncBackwardEuler indicated(ts.mesh, ts.system, 5e-3, {});
  indicated.setRunTimeRegions(indicator);
  EXPECT_TRUE(std::isfinite(stepsApart(indicated, fixed, ts, 6)));
  ASSERT_FALSE(indicated.repartitions().empty());
  EXPECT_GT(indicated.repartitions()[0].fastVertices, 0);
  EXPECT_TRUE(indicated.displacement().allFinite());
  EXPECT_NEAR(lumpedVertexMasses(ts.mesh).sum(), 0.25 * 0.25 * (0.75 * 1000.0 + 0.25 * 200.0), 1e-12);
}

// The loads policy on hexahedra: a pull on the x = 1 face from 2.5 hL to 5.5 hL makes the
// part "tip" (x >= 0.75) fast from step 2, the step the pull starts in, and releases it
// after the pull, once its motion relative to its neighbourhood (weighed by the hexahedra's
// lumped vertex masses) has decayed; without given parts the part is the loaded face grown
// by one ring of hexahedra (the 18 vertices at x >= 0.875).
TEST(HexahedralAsync, LoadsPolicyMakesThePulledPartFast) {
  const std::shared_ptr<const TetMesh> mesh = stiffEndHexBar();
  const std::vector<int> face = test::verticesOnPlanes(*mesh, {1.0});
  const double hL = 5e-3;
  const test::TestBody body(Problem(mesh, test::verticesOnPlanes(*mesh, {0.0}),
                                    test::testSettings(ForceModelType::linear, 60.0, 0.0),
                                    {VertexLoad{face, Eigen::Vector3d(0.0, -0.5, 0.2), 2.5 * hL, 5.5 * hL}}));
  const std::vector<int> tip = test::verticesBeyond(body.mesh, 0.75);
  RunTimeRegionOptions parts;
  parts.loads = true;
  parts.loadsParts = {{"tip", tip, 4}};
  parts.minDwell = 4;
  RunTimeRegionOptions grown;
  grown.loads = true;
  grown.loadsRatio = 4;
  grown.loadsRings = 1;
  AsyncBackwardEuler adaptive(body.mesh, body.system, hL, {}), fromFace(body.mesh, body.system, hL, {});
  adaptive.setRunTimeRegions(parts);
  fromFace.setRunTimeRegions(grown);
  for (int k = 0; k < 60; ++k) adaptive.step();
  for (int k = 0; k < 4; ++k) fromFace.step();
  const std::vector<RepartitionRecord>& records = adaptive.repartitions();
  ASSERT_EQ(records.size(), 2U) << (records.empty() ? "" : records[0].reason);
  EXPECT_EQ(records[0].step, 2);
  EXPECT_EQ(records[0].fastVertices, static_cast<int>(tip.size()));
  EXPECT_GT(records[1].step, 5 + parts.minDwell);
  EXPECT_EQ(records[1].regions, 0);
  ASSERT_FALSE(fromFace.repartitions().empty());
  EXPECT_EQ(fromFace.repartitions()[0].fastVertices, 18);
}

/// Relative difference of the states after 5 large steps of the async integrator (tip
/// region at m = 4, free, damped) with the given force model and the linear one, from the
/// random state scaled by amplitude.
double differenceFromLinear(ForceModelType type, double amplitude) {
  test::TestSystem linear = hexTestSystem(test::testSettings(ForceModelType::linear, 0.1, 1e-3), amplitude);
  test::TestSystem nonlinear = hexTestSystem(test::testSettings(type, 0.1, 1e-3), amplitude);
  linear.system.externalForce = nullptr;
  nonlinear.system.externalForce = nullptr;
  AsyncBackwardEuler a(linear.mesh, linear.system, 2e-3, tipRegion(linear.mesh, 4));
  AsyncBackwardEuler b(nonlinear.mesh, nonlinear.system, 2e-3, tipRegion(nonlinear.mesh, 4));
  return stepsApart(a, b, linear, 5);
}

// Corotational, StVK and neo-Hookean hexahedra under the async integrator are linear FEM at small
// amplitudes (the forces are linearized at each large step's start; they differ from linear
// FEM at second order in the strain, here ~1e-4 at amplitude 0.01): bound 1e-3 relative. At
// 100x the amplitude the difference must grow at least 10x, or the nonlinear forces never
// acted.
TEST(HexahedralAsync, NonlinearModelsAreLinearAtSmallAmplitude) {
  for (const ForceModelType type : {ForceModelType::corotational, ForceModelType::stvk, ForceModelType::neoHookean}) {
    const double small = differenceFromLinear(type, 0.01), large = differenceFromLinear(type, 1.0);
    EXPECT_LT(small, 1e-3) << toString(type);
    EXPECT_GT(large, 10.0 * small) << toString(type);
    std::printf("hexahedra, %s async vs linear async: %.2e at amplitude 0.01, %.2e at 1\n", toString(type).c_str(),
                small, large);
  }
}

// Region proposal on hexahedra: every element's highest frequency (24 x 24, lumped mass)
// bounds the assembled bar's highest frequency (lumped mass, clamped) from above, as the
// element eigenvalue inequality says, within round-off (1e-10 relative), and not by far
// (the bound is within 2x here). The proposal marks the stiff end (16x the soft wave speed),
// and its modal check runs on the hexahedral K and M.
TEST(HexahedralAsync, ElementFrequenciesBoundTheMeshAndMarkTheStiffEnd) {
  const std::shared_ptr<const TetMesh> mesh = stiffEndHexBar();
  const Eigen::VectorXd omega = elementMaxFrequencies(*mesh);
  const FreeDofs freeDofs = FreeDofs::fromFixedVertices(mesh->numVertices(), test::verticesOnPlanes(*mesh, {0.0}));
  const std::vector<int>& free = freeDofs.freeToFull();
  const Eigen::MatrixXd k(hexLinearStiffnessMatrix(*mesh)), m(hexMassMatrix(*mesh, MassType::lumped));
  Eigen::VectorXd massRoot(static_cast<Eigen::Index>(free.size()));
  for (std::size_t a = 0; a < free.size(); ++a) massRoot[static_cast<Eigen::Index>(a)] = std::sqrt(m(free[a], free[a]));
  Eigen::MatrixXd scaled(massRoot.size(), massRoot.size());
  for (std::size_t a = 0; a < free.size(); ++a)
    for (std::size_t b = 0; b < free.size(); ++b)
      scaled(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) =
          k(free[a], free[b]) / (massRoot[static_cast<Eigen::Index>(a)] * massRoot[static_cast<Eigen::Index>(b)]);
  const double highest = std::sqrt(
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(scaled, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff());
  EXPECT_LE(highest, omega.maxCoeff() * (1.0 + 1e-10));
  EXPECT_GE(highest, 0.5 * omega.maxCoeff());
  RegionProposalOptions options;
  options.largeTimestep = 1e-2;
  const RegionProposal proposal = proposeRegions(*mesh, freeDofs, options);
  ASSERT_EQ(proposal.regions.size(), 1U);
  for (const int v : test::verticesBeyond(*mesh, 0.75 + 1e-9))
    EXPECT_TRUE(
        std::binary_search(proposal.regions[0].region.vertices.begin(), proposal.regions[0].region.vertices.end(), v))
        << "vertex " << v;
  // The modal check assembles the hexahedral K and M (vibrationMatrices) and decides.
  options.modalCheck = true;
  const RegionProposal checked = proposeRegions(*mesh, freeDofs, options, MassType::lumped);
  EXPECT_EQ(checked.decidedBy, RegionProposalPath::modalCheck) << regionProposalSummary(checked);
  std::printf("hexahedra: highest frequency of the bar %.4g rad/s, largest element frequency %.4g rad/s; %s\n", highest,
              omega.maxCoeff(), regionProposalSummary(checked).c_str());
}

}  // namespace
}  // namespace asyncfem
