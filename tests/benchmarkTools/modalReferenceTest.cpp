// SPDX-License-Identifier: BSD-3-Clause
// The exact modal reference against closed-form single-DOF solutions and a fine
// trapezoidal run; the error metric of a run against itself.
#include <gtest/gtest.h>

#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/benchmarkTools/modalReference.hpp>
#include <asyncfem/benchmarkTools/sceneReference.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <cmath>
#include <nlohmann/json.hpp>

namespace asyncfem {
namespace {

// |a - b| <= tol * max(1, |a|, |b|), the project's scaled tolerance.
void expectClose(double a, double b, double tol) {
  EXPECT_LE(std::abs(a - b), tol * std::max({1.0, std::abs(a), std::abs(b)})) << a << " vs " << b;
}

// Unit-step response of m x'' + c x' + k x = F (from rest), underdamped, in closed form.
double stepResponse(double m, double c, double k, double force, double t) {
  if (t <= 0.0) return 0.0;
  const double omega = std::sqrt(k / m), zeta = c / (2.0 * std::sqrt(k * m));
  const double omegaD = omega * std::sqrt(1.0 - zeta * zeta);
  return force / k *
         (1.0 - std::exp(-zeta * omega * t) *
                    (std::cos(omegaD * t) + zeta / std::sqrt(1.0 - zeta * zeta) * std::sin(omegaD * t)));
}

TEST(DampedOscillator, MatchesClosedFormsInEveryDampingRegime) {
  // Tolerance 1e-12: both sides are a handful of exp/cos evaluations.
  const double lambda = 400.0;         // omega = 20
  for (const double c : {0.0, 4.0}) {  // undamped, zeta = 0.1
    double q = 0.0, rate = 0.0;
    advanceDampedOscillator(lambda, c, 3.0, 0.37, q, rate);
    expectClose(q, stepResponse(1.0, c, lambda, 3.0, 0.37), 1e-12);
  }
  {  // Critical damping, free decay from q0 = 1: q = (1 + omega t) e^{-omega t}.
    double q = 1.0, rate = 0.0;
    advanceDampedOscillator(lambda, 40.0, 0.0, 0.1, q, rate);
    expectClose(q, (1.0 + 2.0) * std::exp(-2.0), 1e-12);
  }
  {  // Overdamped, c = 1e6: roots r1 = -lambda/(mu+g) ~ -4e-4, r2 ~ -1e6; free decay from q0 = 1.
    const double c = 1e6, mu = c / 2, g = std::sqrt(mu * mu - lambda);
    const double r1 = -lambda / (mu + g), r2 = -(mu + g);
    // q = A e^{r1 t} + B e^{r2 t}, A + B = 1, r1 A + r2 B = 0.
    const double A = r2 / (r2 - r1), B = 1.0 - A;
    double q = 1.0, rate = 0.0;
    advanceDampedOscillator(lambda, c, 0.0, 2.0, q, rate);
    expectClose(q, A * std::exp(r1 * 2.0) + B * std::exp(r2 * 2.0), 1e-12);
    EXPECT_TRUE(std::isfinite(rate));
  }
  {  // Rigid mode with damping: q' -> p / c.
    double q = 0.0, rate = 0.0;
    advanceDampedOscillator(0.0, 2.0, 4.0, 10.0, q, rate);
    expectClose(rate, 2.0 * (1.0 - std::exp(-20.0)), 1e-12);
  }
  {  // Splitting one interval into two gives the same state.
    double q1 = 0.3, r1 = -1.0, q2 = 0.3, r2 = -1.0;
    advanceDampedOscillator(lambda, 4.0, 1.5, 0.2, q1, r1);
    advanceDampedOscillator(lambda, 4.0, 1.5, 0.05, q2, r2);
    advanceDampedOscillator(lambda, 4.0, 1.5, 0.15, q2, r2);
    expectClose(q1, q2, 1e-12);
    expectClose(r1, r2, 1e-12);
  }
}

// A spring-mass system: 3 DOFs, M = m I, K = k I, Rayleigh damping.
struct SpringMass {
  Eigen::SparseMatrix<double> mass, stiffness;
  FreeDofs free{3, {}};
  SpringMass(double m, double k) : mass(3, 3), stiffness(3, 3) {
    for (int i = 0; i < 3; ++i) {
      mass.insert(i, i) = m;
      stiffness.insert(i, i) = k;
    }
    mass.makeCompressed();
    stiffness.makeCompressed();
  }
};

TEST(ModalReference, ReproducesSpringMassPullAndRelease) {
  // m = 2, k = 800 (omega = 20), alpha = 0.5, beta = 1e-3: c = alpha m + beta k = 1.8.
  const double m = 2.0, k = 800.0, alpha = 0.5, beta = 1e-3, force = 5.0, release = 0.3;
  SpringMass system(m, k);
  ModalReference reference(system.mass, system.stiffness, system.free, alpha, beta);
  PiecewiseConstantLoad load;
  load.breakpoints = {release};
  Eigen::VectorXd f = Eigen::VectorXd::Zero(3);
  f[1] = force;
  load.forces = {f, Eigen::VectorXd::Zero(3)};
  std::vector<double> times;
  for (int i = 1; i <= 40; ++i) times.push_back(0.025 * i);
  const std::vector<Eigen::VectorXd> u = reference.displacements(load, times);
  const double c = alpha * m + beta * k;
  for (std::size_t i = 0; i < times.size(); ++i) {
    // Superposition: pull = step at 0 minus step at the release time.
    const double exact = stepResponse(m, c, k, force, times[i]) - stepResponse(m, c, k, force, times[i] - release);
    // 1e-10: the eigendecomposition of a 3 x 3 diagonal pencil is exact to round-off.
    expectClose(u[i][1], exact, 1e-10);
    EXPECT_EQ(u[i][0], 0.0);
  }
}

TEST(ModalReference, ReproducesSpringMassImpulse) {
  const double m = 0.5, k = 200.0, impulse = 0.7, time = 0.1;  // omega = 20, undamped
  SpringMass system(m, k);
  ModalReference reference(system.mass, system.stiffness, system.free, 0.0, 0.0);
  PiecewiseConstantLoad load;
  load.forces = {Eigen::VectorXd()};
  Eigen::VectorXd I = Eigen::VectorXd::Zero(3);
  I[2] = impulse;
  load.impulses.push_back({time, I});
  const std::vector<Eigen::VectorXd> u = reference.displacements(load, {0.05, 0.1, 0.2, 0.77});
  EXPECT_EQ(u[0][2], 0.0);
  EXPECT_EQ(u[1][2], 0.0);  // recorded before the impulse at the same time
  for (const auto& [index, t] : {std::pair{2, 0.2}, std::pair{3, 0.77}}) {
    expectClose(u[static_cast<std::size_t>(index)][2], impulse / (m * 20.0) * std::sin(20.0 * (t - time)), 1e-10);
  }
}

Scene smallBoxScene(const std::string& integrator, double timestep) {
  const nlohmann::json json = {{"mesh", {{"generator", "box"}, {"size", {0.4, 0.1, 0.1}}, {"cells", {4, 1, 1}}}},
                               {"fixed", {{"sets", {"xmin"}}}},
                               {"gravity", {0, -9.8, 0}},
                               {"damping", {{"alpha", 0.2}, {"beta", 0.0}}},
                               {"integrator", {{"name", integrator}, {"timestep", timestep}}},
                               {"frames", {{"rate", 100}, {"count", 10}}}};
  return parseScene(json, ".", "box.json");
}

// The exact modal solution of a built scene's linear system.
ModalReference modalReferenceOf(const DynamicSystem& system) {
  Eigen::SparseMatrix<double> K = system.forceModel->createStiffnessMatrix();
  system.forceModel->tangentStiffness(Eigen::VectorXd::Zero(system.numDofs()), K);
  return ModalReference(system.mass, K, system.freeDofs, system.rayleighMass, system.rayleighStiffness);
}

TEST(ModalReference, AgreesWithFineTrapezoidalOnAMesh) {
  // Gravity from t = 0 on a 24-element cantilever; trapezoidal at h = 1e-5 is second order
  // and undamped numerically; 1e-3 relative L2 is far above its error ((omega h)^2 / 12
  // for the modes gravity excites) and far below what a wrong mass weighting would give.
  const Scene scene = smallBoxScene("trapezoidal", 1e-5);
  Simulation simulation = buildSimulation(scene);
  const DynamicSystem& system = simulation.integrator->system();
  const ModalReference reference = modalReferenceOf(system);
  const Trajectory exact = reference.displacements(sceneLoad(scene, simulation), frameTimes(scene, 10));
  Trajectory run;
  for (int frame = 0; frame < 10; ++frame) {
    advanceFrame(simulation, frame);
    run.push_back(simulation.integrator->displacement());
  }
  EXPECT_LT(relativeL2Error(run, exact, {"all", {}}), 1e-3);
  EXPECT_GT(exact.back().norm(), 0.0);
}

TEST(ModalReference, MotionKeptPerBandMeasuresAmplitudePerFrequency) {
  const Scene scene = smallBoxScene("backward-euler", 1e-3);
  Simulation simulation = buildSimulation(scene);
  const DynamicSystem& system = simulation.integrator->system();
  const ModalReference reference = modalReferenceOf(system);
  const Trajectory exact = reference.displacements(sceneLoad(scene, simulation), frameTimes(scene, 10));
  // Modal coordinates of M-orthonormal modes keep the M-norm (Parseval): |q|^2 = u^T M u.
  const Eigen::VectorXd& u = exact.back();
  const double energyNorm = u.dot(system.mass * u);
  ASSERT_GT(energyNorm, 0.0);
  // Relative 1e-9: the eigenvectors are M-orthonormal to round-off of a dense solve.
  EXPECT_NEAR(reference.modalCoordinates(u).squaredNorm() / energyNorm, 1.0, 1e-9);
  EXPECT_THROW(reference.modalCoordinates(Eigen::VectorXd::Zero(3)), asyncfem::Error);

  // Bands split at the median frequency: every mode is counted once; the exact solution
  // keeps 1 in each band with motion; a run at half amplitude keeps 0.5 (to round-off).
  const Eigen::VectorXd& lambda = reference.eigenvalues();
  const double median = std::sqrt(lambda[lambda.size() / 2]);
  const std::vector<double> edges{0.0, median};
  const std::vector<ModalBand> same = motionKeptPerBand(reference, exact, exact, edges);
  ASSERT_EQ(same.size(), 2u);
  EXPECT_EQ(same[0].modes + same[1].modes, reference.numFree());
  Trajectory half = exact;
  for (Eigen::VectorXd& frame : half) frame *= 0.5;
  const std::vector<ModalBand> halved = motionKeptPerBand(reference, half, exact, edges);
  for (std::size_t b = 0; b < 2; ++b) {
    if (std::isnan(same[b].kept)) continue;  // no reference motion in the band
    expectClose(same[b].kept, 1.0, 1e-12);
    expectClose(halved[b].kept, 0.5, 1e-12);
  }
  EXPECT_FALSE(std::isnan(same[0].kept)) << "the pulled box must move its low modes";
  EXPECT_THROW(motionKeptPerBand(reference, exact, exact, {1.0, 0.5}), asyncfem::Error);
}

TEST(ErrorMetrics, RunAgainstItselfIsZero) {
  const Scene scene = smallBoxScene("backward-euler", 1e-3);
  Simulation simulation = buildSimulation(scene);
  Trajectory run;
  for (int frame = 0; frame < 5; ++frame) {
    advanceFrame(simulation, frame);
    run.push_back(simulation.integrator->displacement());
  }
  EXPECT_EQ(relativeL2Error(run, run, {"all", {}}), 0.0);
  EXPECT_EQ(relativeL2Error(run, run, {"tip", simulation.mesh->vertexSet("xmax")}), 0.0);
  // A uniformly scaled run: relative error equals the scale change.
  Trajectory scaled = run;
  for (Eigen::VectorXd& u : scaled) u *= 1.1;
  expectClose(relativeL2Error(scaled, run, {"all", {}}), 0.1, 1e-12);
  EXPECT_EQ(vertexDisplacementNorms(run, 0).size(), 5u);
}

TEST(SceneLoad, SplitsPullsIntoPiecesAndKeepsImpulses) {
  nlohmann::json json = {{"mesh", {{"generator", "box"}, {"cells", {2, 1, 1}}}},
                         {"fixed", {{"sets", {"xmin"}}}},
                         {"forces",
                          {{{"type", "pull"}, {"set", "xmax"}, {"force", {0, -4, 0}}, {"window", {0.1, 0.3}}},
                           {{"type", "impulse"}, {"vertices", {0, 0}}, {"impulse", {1, 0, 0}}, {"time", 0.2}}}},
                         {"integrator", {{"name", "backward-euler"}, {"timestep", 0.01}}},
                         {"frames", {{"rate", 50}}}};
  const Scene scene = parseScene(json, ".", "load.json");
  const Simulation simulation = buildSimulation(scene);
  const PiecewiseConstantLoad load = sceneLoad(scene, simulation);
  ASSERT_EQ(load.breakpoints, (std::vector<double>{0.1, 0.3}));
  ASSERT_EQ(load.forces.size(), 3u);
  EXPECT_EQ(load.forces[0].norm(), 0.0);
  EXPECT_NEAR(load.forces[1].sum(), -4.0, 1e-12);
  EXPECT_EQ(load.forces[2].norm(), 0.0);
  ASSERT_EQ(load.impulses.size(), 1u);
  EXPECT_EQ(load.impulses[0].impulse[0], 1.0);  // duplicates count once
}

}  // namespace
}  // namespace asyncfem
