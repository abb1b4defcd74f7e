// SPDX-License-Identifier: BSD-3-Clause
// Nested and touching fast regions (docs/asynchronous-integrator.md, "Nested and touching
// regions", Eqs. N1-N6 and Theorem N): the energy theorem on random hierarchies and on the
// dense step map, momentum, the single-rate and two-level special cases, the step system
// against an independent per-step evaluation of its definition, corotational forces, and
// the ratios that may not share an element.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <memory>
#include <random>
#include <string>

#include "asyncTestSystem.hpp"
#include "nestedDefinition.hpp"

namespace asyncfem {
namespace {

using test::relativeDifference;

/// Up to three levels on a body: each vertex drawn into L, S1 (ratio m1) or S2 (ratio
/// m1 m2) with the given probabilities, so regions nest, touch each other and touch L.
struct Hierarchy {
  std::vector<AsyncRegion> regions;
  std::string describe() const {
    std::string out;
    for (const AsyncRegion& r : regions)
      out += r.name + " ratio " + std::to_string(r.ratio) + " (" + std::to_string(r.vertices.size()) + " v) ";
    return out;
  }
};

Hierarchy randomHierarchy(const TetMesh& mesh, std::mt19937& random, int m1, int m2) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double p1 = 0.2 + 0.4 * uniform(random), p2 = 0.1 + 0.3 * uniform(random);
  Hierarchy h{{{"S1", {}, m1}, {"S2", {}, m1 * m2}}};
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const double draw = uniform(random);
    if (draw < p2) {
      h.regions[1].vertices.push_back(v);
    } else if (draw < p1 + p2) {
      h.regions[0].vertices.push_back(v);
    }
  }
  return h;
}

/// The asynchronous integrator's hierarchy solve on these regions: chosen by itself where
/// they touch or nest, asked for (AsyncSolveMethod::hierarchy) where they do not.
std::unique_ptr<AsyncBackwardEuler> hierarchyIntegrator(DynamicSystem system, double largeTimestep,
                                                        std::vector<AsyncRegion> regions,
                                                        NestedSolve solve = NestedSolve::automatic) {
  AsyncOptions options;
  options.method = AsyncSolveMethod::hierarchy;
  options.nestedSolve = solve;
  return std::make_unique<AsyncBackwardEuler>(std::move(system), largeTimestep, std::move(regions), options);
}

/// The rubber cantilever of testProblems.hpp (4 x 1 x 1 cubes, 48 free DOFs), linear,
/// consistent mass, undamped unless given, no load.
test::TestBody smallBar(double alpha = 0.0, double beta = 0.0, ForceModelType model = ForceModelType::linear) {
  return test::TestBody(test::rubberBarProblem(test::testSettings(model, alpha, beta)));
}

/// Drops regions without a free DOF (a random draw may put only clamped vertices in one).
std::vector<AsyncRegion> withFreeDofs(const test::TestBody& body, std::vector<AsyncRegion> regions) {
  std::vector<AsyncRegion> out;
  for (AsyncRegion& r : regions) {
    bool free = false;
    for (int v : r.vertices) free = free || !body.system.freeDofs.isFixed(3 * v);
    if (free) out.push_back(std::move(r));
  }
  return out;
}

// Theorem N: a free, undamped linear system never gains energy, whatever the hierarchy. The
// energy is computed from the state alone (v^T M v / 2 + u^T K u / 2), so its one-step
// change is the sum of round-off and the dissipation terms of Eq. N7; 1e-12 of E_0 is
// round-off's bound for these ~1e2-unknown systems.
TEST(NestedRegions, RandomHierarchiesNeverGainEnergy) {
  test::TestBody body = smallBar();
  std::mt19937 random(2026);
  const int ratios[][2] = {{2, 2}, {4, 4}, {3, 4}, {8, 2}, {16, 16}, {2, 128}, {5, 3}, {64, 4}};
  int cases = 0;
  for (const auto& pair : ratios)
    for (int draw = 0; draw < 3; ++draw) {
      const Hierarchy h = randomHierarchy(body.mesh, random, pair[0], pair[1]);
      const std::vector<AsyncRegion> regions = withFreeDofs(body, h.regions);
      // hL = 1e-3 keeps most of the energy over a step (the check is sharp); 2e-2 damps the
      // high modes (omega hL up to ~100) the way implicit steps are used.
      const auto integratorOwner = hierarchyIntegrator(body.system, draw == 0 ? 2e-2 : 1e-3, regions);
      AsyncBackwardEuler& integrator = *integratorOwner;
      const test::RandomState start =
          test::randomState(body.system.freeDofs, 100 + cases, test::FixedDofDraws::skipped);
      integrator.setState(start.displacement, start.velocity);
      double energy = integrator.mechanicalEnergy();
      for (int k = 0; k < 4; ++k) {
        integrator.step();
        const double next = integrator.mechanicalEnergy();
        EXPECT_LE(next, energy * (1.0 + 1e-12)) << h.describe() << " step " << k;
        energy = next;
      }
      ++cases;
    }
  EXPECT_EQ(cases, 24);
}

/// The step map Phi of an undamped linear integrator on the free DOFs: [u; v]_{k+1} = Phi
/// [u; v]_k, column by column from unit states.
Eigen::MatrixXd stepMap(Integrator& integrator) {
  const std::vector<int>& free = integrator.system().freeDofs.freeToFull();
  const auto nf = static_cast<Eigen::Index>(free.size());
  const Eigen::Index n = integrator.system().numDofs();
  Eigen::MatrixXd phi(2 * nf, 2 * nf);
  for (Eigen::Index c = 0; c < 2 * nf; ++c) {
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n), v = Eigen::VectorXd::Zero(n);
    (c < nf ? u : v)[free[static_cast<std::size_t>(c % nf)]] = 1.0;
    integrator.setState(u, v, 0.0);
    integrator.step();
    for (Eigen::Index r = 0; r < nf; ++r) {
      phi(r, c) = integrator.displacement()[free[static_cast<std::size_t>(r)]];
      phi(nf + r, c) = integrator.velocity()[free[static_cast<std::size_t>(r)]];
    }
  }
  return phi;
}

/// H = diag(K, M) on the free DOFs: E = x^T H x / 2 for the state x = [u; v].
Eigen::MatrixXd stateEnergyMatrix(const test::TestBody& body) {
  const std::vector<int>& free = body.system.freeDofs.freeToFull();
  const auto nf = static_cast<Eigen::Index>(free.size());
  Eigen::SparseMatrix<double> k = body.system.forceModel->createStiffnessMatrix();
  body.system.forceModel->tangentStiffness(Eigen::VectorXd::Zero(body.mesh.numDofs()), k);
  const Eigen::MatrixXd fullK(k), fullM(body.system.mass);
  Eigen::MatrixXd energy = Eigen::MatrixXd::Zero(2 * nf, 2 * nf);
  for (Eigen::Index a = 0; a < nf; ++a)
    for (Eigen::Index b = 0; b < nf; ++b) {
      energy(a, b) = fullK(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
      energy(nf + a, nf + b) = fullM(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
    }
  return energy;
}

/// Worst one-step energy ratio: the largest eigenvalue of (Phi^T H Phi, H).
double worstEnergyRatio(const Eigen::MatrixXd& phi, const Eigen::MatrixXd& energy) {
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> ratio(phi.transpose() * energy * phi, energy,
                                                                  Eigen::EigenvaluesOnly);
  return ratio.eigenvalues().maxCoeff();
}

double spectralRadius(const Eigen::MatrixXd& phi) {
  return Eigen::EigenSolver<Eigen::MatrixXd>(phi, false).eigenvalues().cwiseAbs().maxCoeff();
}

// The dense step map of small models: its worst one-step energy ratio, the largest
// generalized eigenvalue of (Phi^T H Phi, H) with H = diag(K, M) on the free DOFs, and its
// spectral radius are at most 1. Eigen-solver round-off on these 96 x 96 maps is ~1e-12.
TEST(NestedRegions, DenseStepMapNeverGainsEnergy) {
  test::TestBody body = smallBar();
  const Eigen::MatrixXd energy = stateEnergyMatrix(body);
  std::mt19937 random(7);
  const int ratios[][2] = {{4, 4}, {2, 16}, {16, 16}, {8, 1}};
  for (const auto& pair : ratios)
    for (double hL : {1e-3, 2e-2}) {
      const Hierarchy h = randomHierarchy(body.mesh, random, pair[0], pair[1]);
      const auto integratorOwner = hierarchyIntegrator(body.system, hL, withFreeDofs(body, h.regions));
      AsyncBackwardEuler& integrator = *integratorOwner;
      const Eigen::MatrixXd phi = stepMap(integrator);
      EXPECT_LE(worstEnergyRatio(phi, energy), 1.0 + 1e-10) << h.describe() << " hL " << hL;
      const double radius = spectralRadius(phi);
      EXPECT_LE(radius, 1.0 + 1e-10) << h.describe() << " hL " << hL;
      EXPECT_GT(radius, 0.5) << "a map this contractive would mean the test measures nothing";
    }
}

// The two-level stable coupling (AsyncBackwardEuler, Eqs. A8-A14) by the same dense check:
// one region at ratios 1..64 on the free end of the cantilever, two step sizes.
TEST(NestedRegions, TwoLevelStepMapNeverGainsEnergy) {
  test::TestBody body = smallBar();
  const Eigen::MatrixXd energy = stateEnergyMatrix(body);
  AsyncOptions exact;
  exact.keptFactors.laggedSchur = false;
  for (int ratio : {1, 4, 64})
    for (double hL : {1e-3, 2e-2}) {
      AsyncBackwardEuler integrator(body.system, hL, {{"end", test::verticesBeyond(body.mesh, 0.5), ratio}}, exact);
      const Eigen::MatrixXd phi = stepMap(integrator);
      EXPECT_LE(worstEnergyRatio(phi, energy), 1.0 + 1e-10) << "m " << ratio << " hL " << hL;
      EXPECT_LE(spectralRadius(phi), 1.0 + 1e-10) << "m " << ratio << " hL " << hL;
    }
}

// A free body (nothing clamped, no load, stiffness-proportional damping only, which acts on
// deformation alone) keeps its linear momentum 1^T M v per axis, to the round-off of the
// sparse LU solve (measured 3e-13 of |M v|; bound 1e-11).
TEST(NestedRegions, FreeBodyKeepsMomentum) {
  test::TestBody body = smallBar(0.0, 2e-3);
  body.system.freeDofs = FreeDofs(body.mesh.numDofs(), {});
  std::mt19937 random(11);
  const Hierarchy h = randomHierarchy(body.mesh, random, 4, 8);
  const auto integratorOwner = hierarchyIntegrator(body.system, 0.01, h.regions);
  AsyncBackwardEuler& integrator = *integratorOwner;
  const test::RandomState start = test::randomState(body.system.freeDofs, 5, test::FixedDofDraws::skipped);
  integrator.setState(start.displacement, start.velocity);
  const auto momentum = [&](const Eigen::VectorXd& v) {
    const Eigen::VectorXd mv = body.system.mass * v;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (Eigen::Index i = 0; i < mv.size(); ++i) p[i % 3] += mv[i];
    return p;
  };
  const Eigen::Vector3d p0 = momentum(start.velocity);
  const double scale = (body.system.mass * start.velocity).norm();
  for (int k = 0; k < 5; ++k) {
    integrator.step();
    EXPECT_LT((momentum(integrator.velocity()) - p0).norm(), 1e-11 * scale) << "step " << k;
  }
}

// Every ratio 1 (two touching regions and L): the step is single-rate backward Euler. Both
// solve the same equations (here by sparse LU, there by dense LU): 1e-11 relative.
TEST(NestedRegions, AllRatiosOneIsBackwardEuler) {
  test::TestSystem ts = test::makeTestSystem(0.3, 2e-3);
  std::vector<AsyncRegion> regions{{"a", test::verticesBeyond(ts.mesh, 0.5), 1},
                                   {"b", test::verticesOnPlanes(ts.mesh, {0.25, 0.375}), 1}};
  const auto nestedOwner = hierarchyIntegrator(ts.system, 5e-3, regions);
  AsyncBackwardEuler& nested = *nestedOwner;
  nested.setState(ts.u0, ts.v0);
  test::DenseBackwardEuler reference(ts.system);
  Eigen::VectorXd u = ts.u0, v = ts.v0;
  for (int k = 0; k < 5; ++k) {
    reference.step(5e-3, k * 5e-3, u, v);
    nested.step();
  }
  EXPECT_LT(relativeDifference(nested.displacement(), u), 1e-11);
  EXPECT_LT(relativeDifference(nested.velocity(), v), 1e-11);
}

/// Five steps of the two-level stable coupling (AsyncBackwardEuler) and of the nested
/// integrator on the same regions; the largest relative difference of u and v.
double twoLevelDifference(const test::TestSystem& ts, const std::vector<AsyncRegion>& regions) {
  AsyncOptions exact;
  exact.keptFactors.laggedSchur = false;
  AsyncBackwardEuler twoLevel(ts.system, 4e-3, regions, exact);
  const auto nestedOwner = hierarchyIntegrator(ts.system, 4e-3, regions);
  AsyncBackwardEuler& nested = *nestedOwner;
  twoLevel.setState(ts.u0, ts.v0);
  nested.setState(ts.u0, ts.v0);
  for (int k = 0; k < 5; ++k) {
    twoLevel.step();
    nested.step();
  }
  return std::max(relativeDifference(twoLevel.displacement(), nested.displacement()),
                  relativeDifference(twoLevel.velocity(), nested.velocity()));
}

// Two levels (regions that touch only L) are the stable coupling of Eqs. A8-A12, solved
// there by Schur complements and here by one sparse LU: equal to round-off (1e-10 relative,
// after five steps of systems with condition numbers ~1e6), damped, loaded at every substep,
// linear and corotational (both linearize at the start of the large step).
TEST(NestedRegions, TwoLevelsAreTheStableCoupling) {
  for (ForceModelType model : {ForceModelType::linear, ForceModelType::corotational}) {
    const test::TestSystem ts = test::makeTestSystem(test::testSettings(model, 0.2, 1e-3));
    const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.75), 8},
                                           {"middle", test::verticesOnPlanes(ts.mesh, {0.375}), 3}};
    EXPECT_LT(twoLevelDifference(ts, regions), 1e-10) << (model == ForceModelType::linear ? "linear" : "corotational");
  }
}

// The sparse step system (unknowns v and w, Eqs. N4-N5) against Eq. N3 evaluated directly
// from its solution: three nested levels (8 inside 2, and 16 touching both), damped, loaded.
// Round-off in the sums: 1e-10 of the largest term.
TEST(NestedRegions, StepSystemSolvesTheDefinition) {
  test::TestSystem ts = test::makeTestSystem(0.4, 1e-3);
  const std::vector<AsyncRegion> regions{{"outer", test::verticesBeyond(ts.mesh, 0.5), 2},
                                         {"inner", test::verticesBeyond(ts.mesh, 0.875), 8},
                                         {"slab", test::verticesOnPlanes(ts.mesh, {0.375}), 16}};
  std::vector<AsyncRegion> split = regions;
  // "outer" keeps only what "inner" does not take.
  split[0].vertices.clear();
  for (int v : regions[0].vertices)
    if (ts.mesh.restPosition(v).x() < 0.875 - 1e-12) split[0].vertices.push_back(v);
  const auto nestedOwner = hierarchyIntegrator(ts.system, 4e-3, split);
  AsyncBackwardEuler& nested = *nestedOwner;
  EXPECT_TRUE(nested.partition().touching());
  EXPECT_EQ(nested.partition().levels(), (std::vector<int>{1, 2, 8, 16}));
  nested.setState(ts.u0, ts.v0);
  nested.step();
  EXPECT_LT(test::nestedDefinitionResidual(ts, nested, ts.u0, ts.v0, 4e-3, 0.0), 1e-10);
  const Eigen::VectorXd u1 = nested.displacement(), v1 = nested.velocity();
  nested.step();
  EXPECT_LT(test::nestedDefinitionResidual(ts, nested, u1, v1, 4e-3, 4e-3), 1e-10);
}

// Corotational forces are linearized at the start of each large step; at tiny amplitudes
// (rotations ~|grad u| ~ 1e-5 here) the nested corotational run equals the linear one to
// second order: 1e-5 relative is a loose bound. At 100x the amplitude the difference must
// grow (it is relative, so about 100x): it fails if the corotational forces never acted.
TEST(NestedRegions, CorotationalWithinTheLinearizationBound) {
  test::TestSystem linear = test::makeTestSystem(0.1, 1e-3);
  test::TestSystem corotational = test::makeTestSystem(test::testSettings(ForceModelType::corotational, 0.1, 1e-3));
  linear.system.externalForce = nullptr;
  corotational.system.externalForce = nullptr;
  std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(linear.mesh, 0.875), 16}, {"end", {}, 4}};
  for (int v : test::verticesBeyond(linear.mesh, 0.625))
    if (linear.mesh.restPosition(v).x() < 0.875 - 1e-12) regions[1].vertices.push_back(v);
  const auto difference = [&](double amplitude) {
    const auto aOwner = hierarchyIntegrator(linear.system, 2e-3, regions);
    const auto bOwner = hierarchyIntegrator(corotational.system, 2e-3, regions);
    AsyncBackwardEuler& a = *aOwner;
    AsyncBackwardEuler& b = *bOwner;
    a.setState(amplitude * linear.u0, amplitude * linear.v0);
    b.setState(amplitude * linear.u0, amplitude * linear.v0);
    for (int k = 0; k < 5; ++k) {
      a.step();
      b.step();
    }
    return relativeDifference(a.displacement(), b.displacement());
  };
  const double tiny = difference(1e-3), larger = difference(1e-1);
  EXPECT_LT(tiny, 1e-5);
  EXPECT_GT(larger, 10.0 * tiny) << "the corotational forces did not act at all";
}

// The structured solve (Eqs. N9-N12) against the LU of the whole step system (Eq. N8), on
// random chains of three and four levels (nested, touching each other and L), damped and
// loaded, linear and corotational, over several large steps (the corotational runs
// refactor every step). Both solve the same system exactly; 1e-10 of the largest
// displacement bounds their round-off (measured at most 4.2e-13), far below any error of the
// structure (order one).
TEST(NestedRegions, StructuredSolveEqualsTheLU) {
  std::mt19937 random(20261202);
  const std::vector<std::vector<int>> chains{{2, 4}, {4, 8}, {2, 16}, {8, 2}};
  int compared = 0;
  for (ForceModelType model : {ForceModelType::linear, ForceModelType::corotational}) {
    for (const std::vector<int>& chain : chains) {
      test::TestSystem ts = test::makeTestSystem(test::testSettings(model, 0.3, 2e-3));
      std::uniform_real_distribution<double> uniform(0.0, 1.0);
      std::vector<AsyncRegion> regions{{"S1", {}, chain[0]}, {"S2", {}, chain[0] * chain[1]}, {"S3", {}, 0}};
      regions[2].ratio = regions[1].ratio * 2;
      for (int v = 0; v < ts.mesh.numVertices(); ++v) {
        const double draw = uniform(random);
        if (draw < 0.1) {
          regions[2].vertices.push_back(v);
        } else if (draw < 0.3) {
          regions[1].vertices.push_back(v);
        } else if (draw < 0.6) {
          regions[0].vertices.push_back(v);
        }
      }
      std::vector<AsyncRegion> kept;
      for (AsyncRegion& r : regions) {
        bool free = false;
        for (int v : r.vertices) free = free || !ts.system.freeDofs.isFixed(3 * v);
        if (free) kept.push_back(std::move(r));
      }
      const auto structuredOwner = hierarchyIntegrator(ts.system, 3e-3, kept, NestedSolve::structured);
      AsyncBackwardEuler& structured = *structuredOwner;
      const auto luOwner = hierarchyIntegrator(ts.system, 3e-3, kept, NestedSolve::lu);
      AsyncBackwardEuler& lu = *luOwner;
      // The report is available before the first step (the simulator prints it then).
      EXPECT_EQ(structured.report().lines.front(),
                "async step solver: hierarchy (regions that touch or nest, or on request)");
      structured.setState(ts.u0, ts.v0);
      lu.setState(ts.u0, ts.v0);
      for (int k = 0; k < 4; ++k) {
        structured.step();
        lu.step();
      }
      EXPECT_TRUE(structured.hierarchyByLevel());
      EXPECT_FALSE(lu.hierarchyByLevel());
      const std::string label = std::string(model == ForceModelType::linear ? "linear" : "corotational") + " chain " +
                                std::to_string(chain[0]) + "x" + std::to_string(chain[1]);
      EXPECT_LT(relativeDifference(structured.displacement(), lu.displacement()), 1e-10) << label;
      EXPECT_LT(relativeDifference(structured.velocity(), lu.velocity()), 1e-10) << label;
      // Every step's unknowns, not only the end state (the solve completes them on demand).
      const int last = static_cast<int>(ts.system.freeDofs.freeToFull().size()) - 1;
      for (int d : {0, last / 2, last}) {
        EXPECT_LT(relativeDifference(structured.stepVelocities(d), lu.stepVelocities(d)), 1e-10) << label;
        EXPECT_LT(relativeDifference(structured.stepDisplacements(d), lu.stepDisplacements(d)), 1e-10) << label;
      }
      const RunReport report = structured.report();
      ASSERT_GE(report.lines.size(), 3u);
      EXPECT_NE(report.lines[2].find("structured solve"), std::string::npos) << report.lines[2];
      ++compared;
    }
  }
  EXPECT_EQ(compared, 8);
}

// Counts that do not form a chain (3 and 4 apart) run the LU under "automatic" and say why;
// asking for the structured solve is refused by name.
TEST(NestedRegions, StructuredSolveNeedsAChain) {
  test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const std::vector<AsyncRegion> regions{{"tip", test::verticesBeyond(ts.mesh, 0.875), 4},
                                         {"apart", test::verticesOnPlanes(ts.mesh, {0.375}), 3}};
  const auto automaticOwner = hierarchyIntegrator(ts.system, 1e-2, regions);
  AsyncBackwardEuler& automatic = *automaticOwner;
  automatic.setState(ts.u0, ts.v0);
  automatic.step();
  EXPECT_FALSE(automatic.hierarchyByLevel());
  const RunReport report = automatic.report();
  const auto said = [&report](const std::string& text) {
    for (const std::string& line : report.lines)
      if (line.find(text) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(said("async step solver: hierarchy"));
  EXPECT_TRUE(said("do not divide one another in a chain"));
  try {
    (void)hierarchyIntegrator(ts.system, 1e-2, regions, NestedSolve::structured);
    FAIL() << "the structured solve accepted counts 1, 3, 4";
  } catch (const ValidationError& e) {
    EXPECT_NE(std::string(e.what()).find("chain"), std::string::npos) << e.what();
  }
  EXPECT_EQ(parseNestedSolve("lu"), NestedSolve::lu);
  EXPECT_THROW(parseNestedSolve("LU"), ValidationError);
}

// Ratios that share an element must divide one another (Eq. N6); regions that do not share
// one may have any ratios.
TEST(NestedRegions, RatiosThatShareAnElementMustDivide) {
  test::TestSystem ts = test::makeTestSystem(0.0, 0.0);
  const std::vector<int> tip = test::verticesBeyond(ts.mesh, 0.875);
  std::vector<int> beside;
  for (int v : test::verticesOnPlanes(ts.mesh, {0.75})) beside.push_back(v);
  try {
    (void)hierarchyIntegrator(ts.system, 1e-2, {{"tip", tip, 4}, {"beside", beside, 3}});
    FAIL() << "ratios 3 and 4 on one element were accepted";
  } catch (const ValidationError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("element "), std::string::npos) << what;
    EXPECT_NE(what.find("'tip' (ratio 4)"), std::string::npos) << what;
    EXPECT_NE(what.find("'beside' (ratio 3)"), std::string::npos) << what;
  }
  const std::vector<int> apart = test::verticesOnPlanes(ts.mesh, {0.375});
  const auto fineOwner = hierarchyIntegrator(ts.system, 1e-2, {{"tip", tip, 4}, {"apart", apart, 3}});
  AsyncBackwardEuler& fine = *fineOwner;
  EXPECT_EQ(fine.partition().units(), 12);
  EXPECT_FALSE(fine.partition().touching());
  EXPECT_THROW(hierarchyIntegrator(ts.system, 1e-2, {{"tip", tip, 4}, {"again", {tip[0]}, 8}}), ValidationError);
}

}  // namespace
}  // namespace asyncfem
