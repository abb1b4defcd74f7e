// SPDX-License-Identifier: BSD-3-Clause
// The PETSc backend against the single-process CHOLMOD integrators, across 1, 2 and 3
// ranks (ctest runs this executable under mpiexec -n 1, 2, 3), and its failure paths.
// Every test is collective: all ranks run it; trajectories live on rank 0, so the
// comparisons run there, after every collective call of the test.
#include <gtest/gtest.h>
#include <mpi.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/integratorOptions.hpp>
#include <asyncfem/integrator/trapezoidal.hpp>
#include <asyncfem/petscBackend/partition.hpp>
#include <asyncfem/petscBackend/petscRuntime.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/petscBackend/problemSettings.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "../hexElements/hexBar.hpp"
#include "cantilever.hpp"

namespace asyncfem::test {
namespace {

int worldRank() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

int worldSize() {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

constexpr double kTimestep = 0.02;
constexpr int kSteps = 15;
constexpr double kSolverTolerance = 1e-10;  // relative residual of the iterative solves

/// The cantilever of cantilever.hpp, x = 0 face fixed, sagging under gravity.
TetMesh beamMesh() { return rubberCantilever(); }

const Eigen::Vector3d kGravity(0.0, -9.81, 0.0);

PetscSimulationSettings beamSettings(const TetMesh& mesh, PetscIntegratorKind integrator, PetscForceModelKind model,
                                     PetscSolverKind solver) {
  PetscSimulationSettings settings;
  settings.integrator = integrator;
  settings.forceModel = model;
  settings.timestep = kTimestep;
  settings.fixedVertices = mesh.vertexSet("xmin");
  settings.gravity = kGravity;
  settings.solver.kind = solver;
  settings.solver.relativeTolerance = kSolverTolerance;
  return settings;
}

/// The single-process reference: the integrator library's BackwardEuler or Trapezoidal
/// with CHOLMOD on the same mesh, fixed vertices and gravity M g.
std::vector<Eigen::VectorXd> computeCholmodTrajectory(const TetMesh& mesh, PetscIntegratorKind integrator,
                                                      PetscForceModelKind model, double alpha = 0.0,
                                                      double beta = 0.0) {
  auto assembler = std::make_shared<const MatrixAssembler>(mesh);
  DynamicSystem system;
  if (model == PetscForceModelKind::linear) {
    system.forceModel = std::make_shared<LinearForceModel>(linearStiffnessMatrix(mesh, *assembler));
  } else {
    system.forceModel = std::make_shared<CorotationalLinearFEM>(mesh, assembler, TangentKind::simple);
  }
  system.mass = massMatrix(mesh, *assembler, MassType::consistent);
  system.freeDofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
  system.rayleighMass = alpha;
  system.rayleighStiffness = beta;
  const Eigen::VectorXd gravityForce = system.mass * kGravity.replicate(mesh.numVertices(), 1);
  system.externalForce = [gravityForce](double, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                        Eigen::VectorXd& forces) { forces += gravityForce; };
  std::unique_ptr<Integrator> reference;
  if (integrator == PetscIntegratorKind::backwardEuler) {
    IntegratorOptions exact;  // exact solves, as MUMPS gives (not the default kept factor)
    exact.reuseFactor = false;
    reference = std::make_unique<BackwardEuler>(system, kTimestep, exact);
  } else {
    reference = std::make_unique<Trapezoidal>(system, kTimestep);
  }
  std::vector<Eigen::VectorXd> trajectory;
  for (int k = 0; k < kSteps; ++k) {
    reference->step();
    trajectory.push_back(reference->displacement());
  }
  return trajectory;
}

/// The same, computed once per integrator and model (rank 0 computes while the other
/// ranks wait, so the tests stay short under MPI).
const std::vector<Eigen::VectorXd>& cholmodTrajectory(const TetMesh& mesh, PetscIntegratorKind integrator,
                                                      PetscForceModelKind model) {
  static std::map<std::pair<PetscIntegratorKind, PetscForceModelKind>, std::vector<Eigen::VectorXd>> cache;
  const auto key = std::make_pair(integrator, model);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, computeCholmodTrajectory(mesh, integrator, model)).first;
  return it->second;
}

/// Condition number of the free backward-Euler matrix M + h^2 K at rest (dense, 624
/// DOFs): the factor between a solve's relative residual and its relative error.
double systemConditionNumber(const TetMesh& mesh) {
  MatrixAssembler assembler(mesh);
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
  const Eigen::SparseMatrix<double> full = massMatrix(mesh, assembler, MassType::consistent) +
                                           (kTimestep * kTimestep) * linearStiffnessMatrix(mesh, assembler);
  const auto n = static_cast<Eigen::Index>(dofs.numFree());
  const Eigen::MatrixXd dense(full);
  Eigen::MatrixXd free(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) free(i, j) = dense(dofs.freeToFull()[i], dofs.freeToFull()[j]);
  }
  const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(free).eigenvalues();
  return eigenvalues.maxCoeff() / eigenvalues.minCoeff();
}

/// Largest |a_k - b_k|_inf over the steps, relative to the largest |b_k|_inf.
double trajectoryDifference(const std::vector<Eigen::VectorXd>& a, const std::vector<Eigen::VectorXd>& b) {
  double difference = 0.0;
  double scale = 0.0;
  for (std::size_t k = 0; k < b.size(); ++k) {
    difference = std::max(difference, (a[k] - b[k]).lpNorm<Eigen::Infinity>());
    scale = std::max(scale, b[k].lpNorm<Eigen::Infinity>());
  }
  return difference / std::max(scale, 1e-300);
}

/// Tolerance of a PETSc trajectory against CHOLMOD's. An iterative solve stops at a
/// relative residual of 1e-10, so each step's increment has a relative error of at most
/// kappa * 1e-10 (kappa ~ 4.5e3 here, the condition number of the system matrix); the
/// displacement accumulates h times these increments, whose summed size is about the
/// final displacement for this sagging beam, and a factor 10 covers that sum, the
/// mixing of 2- and max-norms and the corotated tangent's condition number differing
/// from the one at rest: 10 kappa 1e-10 ~ 5e-6. Direct solves are exact up to rounding,
/// kappa * 1e-15 per solve with the same factor: ~5e-11.
double systemConditionNumberCached(const TetMesh& mesh) {
  static const double kappa = systemConditionNumber(mesh);
  return kappa;
}

double comparisonTolerance(const TetMesh& mesh, PetscSolverKind solver) {
  const double kappa = systemConditionNumberCached(mesh);
  const double perStep = solver == PetscSolverKind::mumps ? 1e-15 : kSolverTolerance;
  return 10.0 * kappa * perStep;
}

class PetscVersusCholmod
    : public ::testing::TestWithParam<std::tuple<PetscIntegratorKind, PetscForceModelKind, PetscSolverKind>> {};

TEST_P(PetscVersusCholmod, TrajectoryMatchesToSolverTolerance) {
  const auto [integrator, model, solver] = GetParam();
  const TetMesh mesh = beamMesh();
  const PetscTrajectory petsc = runPetscSimulation(mesh, beamSettings(mesh, integrator, model, solver), kSteps);
  EXPECT_EQ(petsc.stats.ranks, worldSize());
  EXPECT_EQ(petsc.stats.steps, kSteps);
  if (worldRank() != 0) {
    EXPECT_TRUE(petsc.displacements.empty());
    return;
  }
  const std::vector<Eigen::VectorXd>& reference = cholmodTrajectory(mesh, integrator, model);
  ASSERT_EQ(petsc.displacements.size(), reference.size());
  const double tolerance = comparisonTolerance(mesh, solver);
  ASSERT_LT(tolerance, 1e-4) << "the condition number makes the comparison meaningless";
  // The motion is not trivial: the tip sags by more than 1% of the length.
  ASSERT_GT(reference.back().lpNorm<Eigen::Infinity>(), 1e-2);
  EXPECT_LE(trajectoryDifference(petsc.displacements, reference), tolerance)
      << toString(integrator) << " " << toString(model) << " " << toString(solver) << " on " << worldSize()
      << " ranks, " << petsc.stats.solverIterations << " iterations";
}

std::string caseName(const ::testing::TestParamInfo<PetscVersusCholmod::ParamType>& info) {
  std::string name = toString(std::get<1>(info.param)) + "_" + toString(std::get<2>(info.param));
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

INSTANTIATE_TEST_SUITE_P(
    BackwardEuler, PetscVersusCholmod,
    ::testing::Combine(::testing::Values(PetscIntegratorKind::backwardEuler),
                       ::testing::Values(PetscForceModelKind::linear, PetscForceModelKind::corotational),
                       ::testing::Values(PetscSolverKind::cgGamg, PetscSolverKind::cgHypre, PetscSolverKind::mumps)),
    caseName);
INSTANTIATE_TEST_SUITE_P(Trapezoidal, PetscVersusCholmod,
                         ::testing::Combine(::testing::Values(PetscIntegratorKind::trapezoidal),
                                            ::testing::Values(PetscForceModelKind::linear,
                                                              PetscForceModelKind::corotational),
                                            ::testing::Values(PetscSolverKind::cgGamg, PetscSolverKind::mumps)),
                         caseName);

// The backend's settings come from the Problem the single-process path runs: its mass,
// damping, fixed vertices and gravity as they are, its load windows as the time-dependent
// force (f(t) equal to the windows' sum, zero outside them).
TEST(PetscProblemSettings, FollowTheProblem) {
  auto mesh = std::make_shared<const TetMesh>(beamMesh());
  ProblemSettings physics;
  physics.mass = MassType::lumped;
  physics.forceModel = ForceModelType::corotational;
  physics.rayleighAlpha = 0.5;
  physics.rayleighBeta = 2e-3;
  physics.gravity = kGravity;
  VertexLoad pull;
  pull.vertices = {5, 7};
  pull.perVertex = Eigen::Vector3d(0.0, 0.0, 3.0);
  pull.start = 0.1;
  pull.end = 0.2;
  const Problem problem(mesh, {0, 1, 2}, physics, {pull});
  const PetscSimulationSettings settings = petscSettingsForProblem(problem, "trapezoidal", kTimestep);
  EXPECT_EQ(settings.integrator, PetscIntegratorKind::trapezoidal);
  EXPECT_EQ(settings.forceModel, PetscForceModelKind::corotational);
  EXPECT_EQ(settings.massType, MassType::lumped);
  EXPECT_EQ(settings.timestep, kTimestep);
  EXPECT_EQ(settings.rayleighMass, 0.5);
  EXPECT_EQ(settings.rayleighStiffness, 2e-3);
  EXPECT_EQ(settings.fixedVertices, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(settings.gravity, kGravity);
  ASSERT_TRUE(settings.timeDependentForce);
  for (const double t : {0.05, 0.15, 0.25}) {
    Eigen::VectorXd forces = Eigen::VectorXd::Zero(mesh->numDofs());
    settings.timeDependentForce(t, forces);
    const double expected = pull.active(t) ? 3.0 : 0.0;
    EXPECT_EQ(forces[(3 * 5) + 2], expected) << "t = " << t;
    EXPECT_EQ(forces[(3 * 7) + 2], expected) << "t = " << t;
    EXPECT_EQ(forces.cwiseAbs().sum(), 2.0 * expected) << "t = " << t;
  }
  EXPECT_FALSE(
      petscSettingsForProblem(Problem(mesh, {0}, ProblemSettings{}), "backward-euler", kTimestep).timeDependentForce);
}

TEST(PetscProblemSettings, NameWhatTheBackendCannotRun) {
  auto mesh = std::make_shared<const TetMesh>(beamMesh());
  const auto messageOf = [&](const ProblemSettings& physics, const std::string& integrator,
                             const IntegratorOptions& options = {}) {
    try {
      (void)petscSettingsForProblem(Problem(mesh, {0}, physics), integrator, kTimestep, options);
    } catch (const ValidationError& error) {
      return std::string(error.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(messageOf(ProblemSettings{}, "async"),
            "integrator \"async\" is not available on the PETSc backend (it runs backward-euler and trapezoidal)");
  ProblemSettings neoHookean;
  neoHookean.forceModel = ForceModelType::neoHookean;
  IntegratorOptions newton;
  newton.maxIterations = 4;
  EXPECT_EQ(messageOf(neoHookean, "backward-euler", newton), "(no error)");
  EXPECT_EQ(messageOf(neoHookean, "trapezoidal", newton),
            "integrator.options.maxIterations: Newton iterations run with backward-euler only on the PETSc backend "
            "(the trapezoidal rule takes the linearized step, maxIterations 1)");
  IntegratorOptions dampingAtIterate;
  dampingAtIterate.rayleighStiffnessAtIterate = true;
  EXPECT_EQ(messageOf(neoHookean, "backward-euler", dampingAtIterate),
            "integrator.options.rayleighStiffnessAtIterate: not supported on the PETSc backend (Rayleigh damping "
            "keeps K(u_k) of the step start)");
  // Every force model maps to the backend's, with its tangent and options.
  ProblemSettings exactTangent;
  exactTangent.forceModel = ForceModelType::corotational;
  exactTangent.tangent = TangentKind::exact;
  const PetscSimulationSettings exact =
      petscSettingsForProblem(Problem(mesh, {0}, exactTangent), "backward-euler", kTimestep, newton);
  EXPECT_EQ(exact.forceModel, PetscForceModelKind::corotational);
  EXPECT_EQ(exact.tangent, TangentKind::exact);
  EXPECT_EQ(exact.newton.maxIterations, 4);
  neoHookean.hyperelastic.inversionThreshold = 0.3;
  const PetscSimulationSettings hyperelastic =
      petscSettingsForProblem(Problem(mesh, {0}, neoHookean), "backward-euler", kTimestep);
  EXPECT_EQ(hyperelastic.forceModel, PetscForceModelKind::neoHookean);
  EXPECT_EQ(hyperelastic.hyperelastic.inversionThreshold, 0.3);
  // The settings struct refuses trapezoidal Newton too (for C++ callers).
  PetscSimulationSettings trapezoidalNewton = hyperelastic;
  trapezoidalNewton.integrator = PetscIntegratorKind::trapezoidal;
  trapezoidalNewton.newton.maxIterations = 3;
  EXPECT_THROW(PetscSimulation(*mesh, trapezoidalNewton), ValidationError);
}

// Corotational and linear trajectories differ here by far more than the comparison
// tolerance, so the corotational comparison above could not pass with the wrong model.
TEST(PetscBackend, CorotationalDiffersFromLinear) {
  const TetMesh mesh = beamMesh();
  const PetscTrajectory linear = runPetscSimulation(
      mesh, beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear, PetscSolverKind::mumps),
      kSteps);
  const PetscTrajectory corotational = runPetscSimulation(
      mesh,
      beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::corotational, PetscSolverKind::mumps),
      kSteps);
  if (worldRank() != 0) return;
  EXPECT_GT(trajectoryDifference(corotational.displacements, linear.displacements),
            1e3 * comparisonTolerance(mesh, PetscSolverKind::cgGamg));
}

// Rayleigh damping D = alpha M + beta K(u_k) enters both integrators as in the
// single-process ones (same tolerances as above; the damping only lowers kappa's effect).
TEST(PetscBackend, DampedTrajectoriesMatchCholmod) {
  const TetMesh mesh = beamMesh();
  const double alpha = 0.5;
  const double beta = 2e-3;
  for (const auto& [integrator, model, solver] :
       {std::make_tuple(PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear, PetscSolverKind::cgGamg),
        std::make_tuple(PetscIntegratorKind::trapezoidal, PetscForceModelKind::corotational, PetscSolverKind::mumps)}) {
    PetscSimulationSettings settings = beamSettings(mesh, integrator, model, solver);
    settings.rayleighMass = alpha;
    settings.rayleighStiffness = beta;
    const PetscTrajectory petsc = runPetscSimulation(mesh, settings, kSteps);
    if (worldRank() != 0) continue;
    const std::vector<Eigen::VectorXd> reference = computeCholmodTrajectory(mesh, integrator, model, alpha, beta);
    // The damping changes the motion by far more than the tolerance (it is exercised).
    EXPECT_GT(trajectoryDifference(cholmodTrajectory(mesh, integrator, model), reference), 1e-4);
    EXPECT_LE(trajectoryDifference(petsc.displacements, reference), comparisonTolerance(mesh, solver))
        << toString(integrator) << " " << toString(model);
  }
}

// PETSc options given in the settings reach the solver (and only this simulation's).
TEST(PetscBackend, OptionsDatabasePassesThrough) {
  const TetMesh mesh = beamMesh();
  PetscSimulationSettings settings =
      beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear, PetscSolverKind::cgGamg);
  settings.solver.options = "-ksp_type minres -pc_type jacobi";
  const PetscTrajectory minres = runPetscSimulation(mesh, settings, kSteps);
  EXPECT_EQ(minres.stats.kspType, "minres");
  EXPECT_EQ(minres.stats.pcType, "jacobi");
  settings.solver.options.clear();
  const PetscTrajectory gamg = runPetscSimulation(mesh, settings, 1);
  EXPECT_EQ(gamg.stats.kspType, "cg");
  EXPECT_EQ(gamg.stats.pcType, "gamg");
  if (worldRank() != 0) return;
  const std::vector<Eigen::VectorXd>& reference =
      cholmodTrajectory(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear);
  EXPECT_LE(trajectoryDifference(minres.displacements, reference), comparisonTolerance(mesh, PetscSolverKind::cgGamg));
}

// The METIS partition covers every element with balanced, non-empty parts (METIS's
// default imbalance allowance is 3%; 5% leaves room for rounding on 648 elements).
TEST(PetscBackend, PartitionIsBalanced) {
  const TetMesh mesh = beamMesh();
  for (int parts : {1, 2, 3}) {
    const std::vector<int> partition = partitionElements(mesh, parts);
    ASSERT_EQ(static_cast<int>(partition.size()), mesh.numElements());
    std::vector<int> sizes(static_cast<std::size_t>(parts), 0);
    for (int p : partition) {
      ASSERT_GE(p, 0);
      ASSERT_LT(p, parts);
      ++sizes[static_cast<std::size_t>(p)];
    }
    const double average = static_cast<double>(mesh.numElements()) / parts;
    EXPECT_LE(*std::max_element(sizes.begin(), sizes.end()), 1.05 * average + 1.0) << parts << " parts";
    EXPECT_GT(*std::min_element(sizes.begin(), sizes.end()), 0) << parts << " parts";
  }
  EXPECT_THROW(partitionElements(mesh, 0), ValidationError);
}

// A flat element (four coplanar vertices of the x = 1 face) is detected by the one rank
// that assembles it; every rank must throw, naming that rank and the element, instead
// of the other ranks waiting in the matrix assembly (ctest's timeout guards the hang).
TEST(PetscBackendFailure, DegenerateElementOnOneRankStopsEveryRank) {
  const TetMesh good = beamMesh();
  const std::vector<int>& face = good.vertexSet("xmax");
  Eigen::Matrix4Xi elements(4, good.numElements() + 1);
  elements.leftCols(good.numElements()) = good.elements();
  elements.col(good.numElements()) << face[0], face[1], face[4], face[5];
  std::vector<int> materials(static_cast<std::size_t>(good.numElements()) + 1, 0);
  TetMesh mesh(good.restPositions(), elements, good.materials(), materials);
  mesh.setVertexSet("xmin", good.vertexSet("xmin"));
  const int flat = good.numElements();
  const int owner = partitionElements(mesh, worldSize())[static_cast<std::size_t>(flat)];
  try {
    runPetscSimulation(
        mesh,
        beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear, PetscSolverKind::mumps), 2);
    ADD_FAILURE() << "no exception on rank " << worldRank();
  } catch (const ValidationError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("rank " + std::to_string(owner) + ":"), std::string::npos) << message;
    EXPECT_NE(message.find("element " + std::to_string(flat) + " is degenerate"), std::string::npos) << message;
  }
}

// A force callback that fails on the last rank only, at the third step: every rank
// gets the error (same type, the failing rank named), and the backend stays usable.
TEST(PetscBackendFailure, CallbackThrowingOnOneRankStopsEveryRank) {
  const TetMesh mesh = beamMesh();
  PetscSimulationSettings settings = beamSettings(mesh, PetscIntegratorKind::backwardEuler,
                                                  PetscForceModelKind::corotational, PetscSolverKind::cgGamg);
  const int failing = worldSize() - 1;
  settings.timeDependentForce = [failing](double time, Eigen::VectorXd&) {
    if (worldRank() == failing && time > 2.5 * kTimestep) throw NumericalError("injected failure");
  };
  PetscSimulation simulation(mesh, settings);
  simulation.step();
  simulation.step();
  try {
    simulation.step();
    ADD_FAILURE() << "no exception on rank " << worldRank();
  } catch (const NumericalError& error) {
    EXPECT_EQ(std::string(error.what()), "rank " + std::to_string(failing) + ": injected failure");
  }
  // Still usable afterwards: the collective calls are in step on every rank.
  const PetscTrajectory after = runPetscSimulation(
      mesh, beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear, PetscSolverKind::mumps),
      1);
  EXPECT_EQ(after.stats.steps, 1);
}

// A non-finite external force is reported on every rank with the vertex and time.
TEST(PetscBackendFailure, NonFiniteForceIsReported) {
  const TetMesh mesh = beamMesh();
  PetscSimulationSettings settings =
      beamSettings(mesh, PetscIntegratorKind::trapezoidal, PetscForceModelKind::linear, PetscSolverKind::mumps);
  const int vertex = mesh.vertexSet("xmax").front();
  settings.timeDependentForce = [vertex](double time, Eigen::VectorXd& forces) {
    if (time > 1.5 * kTimestep) forces[(3 * vertex) + 1] = std::nan("");
  };
  try {
    runPetscSimulation(mesh, settings, 3);
    ADD_FAILURE() << "no exception on rank " << worldRank();
  } catch (const NumericalError& error) {
    EXPECT_NE(std::string(error.what()).find("(vertex " + std::to_string(vertex) + ", coordinate 1)"),
              std::string::npos)
        << error.what();
  }
}

// The last rank holds a different (coarser) mesh: every rank stops with the same error
// before any collective call sized by the mesh. Needs two ranks to mean anything: the
// one-rank ctest leaves it out, a direct one-rank run reports it skipped.
TEST(PetscBackendFailure, DifferentMeshOnOneRankStopsEveryRank) {
  if (worldSize() < 2) GTEST_SKIP() << "needs at least 2 ranks (ctest PetscBackend.np2, .np3)";
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(1.0, 0.2, 0.2);
  spec.cells = worldRank() == worldSize() - 1 ? Eigen::Vector3i(11, 3, 3) : Eigen::Vector3i(12, 3, 3);
  const TetMesh mesh = makeBoxMesh(spec);
  try {
    PetscSimulation simulation(mesh, beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear,
                                                  PetscSolverKind::mumps));
    ADD_FAILURE() << "no exception on rank " << worldRank();
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("the ranks hold different meshes"), std::string::npos) << error.what();
  }
}

// A PETSc error (an unknown KSP type from the options) becomes an asyncfem::Error that
// carries PETSc's own message.
TEST(PetscBackendFailure, PetscErrorsBecomeExceptions) {
  const TetMesh mesh = beamMesh();
  PetscSimulationSettings settings =
      beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear, PetscSolverKind::cgGamg);
  settings.solver.options = "-ksp_type no_such_method";
  try {
    PetscSimulation simulation(mesh, settings);
    ADD_FAILURE() << "no exception on rank " << worldRank();
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("PETSc: KSPSetFromOptions failed"), std::string::npos) << message;
    EXPECT_NE(message.find("no_such_method"), std::string::npos) << message;
  }
}

// Bad settings: clear errors on every rank.
TEST(PetscBackendFailure, BadSettingsAreRejected) {
  const TetMesh mesh = beamMesh();
  PetscSimulationSettings settings =
      beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::linear, PetscSolverKind::mumps);
  settings.fixedVertices.push_back(mesh.numVertices());
  EXPECT_THROW(PetscSimulation(mesh, settings), ValidationError);
  settings.fixedVertices.pop_back();
  settings.timestep = -1.0;
  EXPECT_THROW(PetscSimulation(mesh, settings), ValidationError);
  EXPECT_THROW(parsePetscSolverKind("lu"), ValidationError);
  EXPECT_EQ(parsePetscSolverKind("cg-hypre"), PetscSolverKind::cgHypre);
}

// Every force model of the single-process libraries on the PETSc backend: the same
// Problem stepped by the integrator library's BackwardEuler or Trapezoidal (CHOLMOD,
// exact solves) and by the backend with MUMPS, whose element loops run the same force
// model kernels on each rank's elements.
constexpr int kModelSteps = 8;
constexpr double kNewtonTolerance = 1e-10;

struct ModelCase {
  const char* name;
  ProblemSettings physics;
  IntegratorOptions options;  // maxIterations, tolerance, lineSearch
  const char* integrator;
};

ProblemSettings modelPhysics(ForceModelType type) {
  ProblemSettings physics;
  physics.forceModel = type;
  physics.gravity = kGravity;
  return physics;
}

IntegratorOptions newtonOptions() {
  IntegratorOptions options;
  options.maxIterations = 6;
  options.tolerance = kNewtonTolerance;
  options.lineSearch = true;
  return options;
}

/// The cases: the exact corotational tangent (Vega's warp 2) and neo-Hookean with
/// inversion handling under Newton with the line search, StVK and Mooney-Rivlin (its
/// small-strain E, nu close to the beam's) on the linearized step.
ModelCase modelCase(int index) {
  switch (index) {
    case 0: {
      ModelCase c{"corotational_exact_newton", modelPhysics(ForceModelType::corotational), newtonOptions(),
                  "backward-euler"};
      c.physics.tangent = TangentKind::exact;
      return c;
    }
    case 1:
      return {"stvk_linearized", modelPhysics(ForceModelType::stvk), IntegratorOptions{}, "backward-euler"};
    case 2: {
      ModelCase c{"neo_hookean_inversion_newton", modelPhysics(ForceModelType::neoHookean), newtonOptions(),
                  "backward-euler"};
      c.physics.hyperelastic.inversionThreshold = 0.2;
      return c;
    }
    default: {
      ModelCase c{"mooney_rivlin_trapezoidal", modelPhysics(ForceModelType::mooneyRivlin), IntegratorOptions{},
                  "trapezoidal"};
      c.physics.hyperelastic.mooneyRivlin = MooneyRivlinParameters{5e4, 1.2e5, 1.6e6};
      return c;
    }
  }
}

std::shared_ptr<const Problem> modelProblem(const ModelCase& c) {
  auto mesh = std::make_shared<const TetMesh>(beamMesh());
  return std::make_shared<const Problem>(mesh, mesh->vertexSet("xmin"), c.physics);
}

std::vector<Eigen::VectorXd> localModelTrajectory(const Problem& problem, const ModelCase& c) {
  IntegratorOptions options = c.options;
  options.reuseFactor = false;  // exact solves, as MUMPS gives
  std::unique_ptr<Integrator> integrator;
  if (std::string(c.integrator) == "backward-euler") {
    integrator = std::make_unique<BackwardEuler>(problem.dynamicSystem(), kTimestep, options);
  } else {
    integrator = std::make_unique<Trapezoidal>(problem.dynamicSystem(), kTimestep, options);
  }
  std::vector<Eigen::VectorXd> trajectory;
  for (int k = 0; k < kModelSteps; ++k) {
    integrator->step();
    trajectory.push_back(integrator->displacement());
  }
  return trajectory;
}

PetscTrajectory petscModelTrajectory(const Problem& problem, const ModelCase& c) {
  PetscSimulationSettings settings = petscSettingsForProblem(problem, c.integrator, kTimestep, c.options);
  settings.solver.kind = PetscSolverKind::mumps;
  return runPetscSimulation(problem.mesh(), settings, kModelSteps);
}

/// Tolerance against the local run: direct solves on both sides, so the linearized step
/// differs by rounding only (10 kappa 1e-15, as comparisonTolerance); with Newton each
/// side stops at its own iterate with |R| <= 1e-10 |b_0|, an increment error of at most
/// kappa 1e-10 relative per step, with the same factor 10 for accumulation: ~5e-6.
double modelTolerance(const TetMesh& mesh, const ModelCase& c) {
  return c.options.maxIterations > 1 ? 10.0 * systemConditionNumberCached(mesh) * kNewtonTolerance
                                     : comparisonTolerance(mesh, PetscSolverKind::mumps);
}

class PetscForceModels : public ::testing::TestWithParam<int> {};

TEST_P(PetscForceModels, TrajectoryMatchesTheLocalRun) {
  const ModelCase c = modelCase(GetParam());
  const std::shared_ptr<const Problem> problem = modelProblem(c);
  const PetscTrajectory petsc = petscModelTrajectory(*problem, c);
  EXPECT_EQ(petsc.stats.steps, kModelSteps);
  if (c.options.maxIterations > 1) {
    // Newton iterated (more linear systems than steps) and converged within the limit.
    EXPECT_GT(petsc.stats.newtonIterations, kModelSteps);
    EXPECT_LE(petsc.stats.newtonIterations, static_cast<long long>(kModelSteps) * c.options.maxIterations);
  } else {
    EXPECT_EQ(petsc.stats.newtonIterations, kModelSteps);
  }
  if (worldRank() != 0) return;
  const std::vector<Eigen::VectorXd> reference = localModelTrajectory(*problem, c);
  const double tolerance = modelTolerance(problem->mesh(), c);
  ASSERT_GT(reference.back().lpNorm<Eigen::Infinity>(), 1e-3);  // it moved
  // The model is not the linear one: the comparison below has teeth.
  const PetscIntegratorKind kind = parsePetscIntegratorKind(c.integrator);
  const std::vector<Eigen::VectorXd>& linear = cholmodTrajectory(problem->mesh(), kind, PetscForceModelKind::linear);
  const std::vector<Eigen::VectorXd> linearPrefix(linear.begin(), linear.begin() + kModelSteps);
  EXPECT_GT(trajectoryDifference(linearPrefix, reference), 10.0 * tolerance);
  EXPECT_LE(trajectoryDifference(petsc.displacements, reference), tolerance)
      << c.name << " on " << worldSize() << " ranks, " << petsc.stats.newtonIterations << " Newton iterations";
}

INSTANTIATE_TEST_SUITE_P(EveryModel, PetscForceModels, ::testing::Range(0, 4),
                         [](const ::testing::TestParamInfo<int>& info) { return modelCase(info.param).name; });

/// Condition number of M + h^2 K at rest on the free DOFs of a hexahedral mesh (dense).
double hexSystemConditionNumber(const TetMesh& mesh, const std::vector<int>& fixed) {
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), fixed);
  const Eigen::SparseMatrix<double> full =
      hexMassMatrix(mesh, MassType::consistent) + (kTimestep * kTimestep) * hexLinearStiffnessMatrix(mesh);
  const SubmatrixExtractor free(full, dofs.freeToFull(), dofs.freeToFull());
  const Eigen::VectorXd eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Eigen::MatrixXd(free.extract(full))).eigenvalues();
  return eigenvalues.maxCoeff() / eigenvalues.minCoeff();
}

// Hexahedral meshes on the backend: every force model on a bar of 8 x 2 x 2 cubes, each
// against the single-process run of the same Problem (backward Euler, CHOLMOD, the
// linearized step), with MUMPS on every rank count. The rank-local element loops run
// the hexahedral kernels (hexElements), the matrices the 24 x 24 element matrices.
TEST(PetscBackend, HexahedralMeshesMatchTheLocalRun) {
  auto mesh = std::make_shared<const TetMesh>(test::hexBar(2));
  std::vector<int> fixed;
  for (int v = 0; v < mesh->numVertices(); ++v)
    if (mesh->restPosition(v).x() == 0.0) fixed.push_back(v);
  // Direct solves on both sides: rounding only, 10 kappa 1e-15 as comparisonTolerance.
  const double tolerance = 10.0 * hexSystemConditionNumber(*mesh, fixed) * 1e-15;
  ASSERT_LT(tolerance, 1e-6);
  std::vector<Eigen::VectorXd> linear;
  for (const ForceModelType type : {ForceModelType::linear, ForceModelType::corotational, ForceModelType::stvk,
                                    ForceModelType::neoHookean, ForceModelType::mooneyRivlin}) {
    const std::string name = toString(type);
    ModelCase c{name.c_str(), modelPhysics(type), IntegratorOptions{}, "backward-euler"};
    if (type == ForceModelType::mooneyRivlin)
      c.physics.hyperelastic.mooneyRivlin = MooneyRivlinParameters{5e4, 1.2e5, 1.6e6};
    const Problem problem(mesh, fixed, c.physics);
    const PetscTrajectory petsc = petscModelTrajectory(problem, c);
    EXPECT_EQ(petsc.stats.steps, kModelSteps);
    if (worldRank() != 0) continue;
    const std::vector<Eigen::VectorXd> reference = localModelTrajectory(problem, c);
    ASSERT_GT(reference.back().lpNorm<Eigen::Infinity>(), 1e-3);  // it moved
    EXPECT_LE(trajectoryDifference(petsc.displacements, reference), tolerance)
        << toString(type) << " on " << worldSize() << " ranks";
    if (type == ForceModelType::linear) {
      linear = reference;
    } else {  // the nonlinear models differ from the linear one: the comparison has teeth
      EXPECT_GT(trajectoryDifference(linear, reference), 10.0 * tolerance) << toString(type);
    }
  }
}

// An inverted hexahedron (two corners of the top face swapped) is named by the rank that
// assembles it, on every rank.
TEST(PetscBackendFailure, InvertedHexahedronIsNamedOnEveryRank) {
  const TetMesh good = test::hexBar(2);
  HexElements hexahedra = good.hexahedra();
  const int bad = good.numElements() - 1;
  std::swap(hexahedra(4, bad), hexahedra(6, bad));
  const TetMesh mesh(good.restPositions(), hexahedra, good.materials(), good.elementMaterials());
  PetscSimulationSettings settings;
  settings.timestep = kTimestep;
  settings.fixedVertices = {0};
  try {
    PetscSimulation simulation(mesh, settings);
    ADD_FAILURE() << "no exception on rank " << worldRank();
  } catch (const ValidationError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("hexahedron " + std::to_string(bad) + " has det J"), std::string::npos) << message;
  }
}

// A hyperelastic element that fails on one rank (neo-Hookean log J of an element
// flattened by the initial state, inversion handling off) stops every rank with the
// mesh's element number.
TEST(PetscBackendFailure, NonFiniteHyperelasticElementNamesTheMeshElement) {
  const ModelCase c{"neo_hookean", modelPhysics(ForceModelType::neoHookean), IntegratorOptions{}, "backward-euler"};
  const std::shared_ptr<const Problem> problem = modelProblem(c);
  const TetMesh& mesh = problem->mesh();
  PetscSimulationSettings settings = petscSettingsForProblem(*problem, c.integrator, kTimestep);
  settings.solver.kind = PetscSolverKind::mumps;
  PetscSimulation simulation(mesh, settings);
  // Collapse the last element onto its first vertex (its other vertices are free: the
  // beam's x = 1 end).
  const int last = mesh.numElements() - 1;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.numDofs());
  for (int a = 1; a < 4; ++a) {
    const int v = mesh.elements()(a, last);
    u.segment<3>(3 * v) = mesh.restPositions().col(mesh.elements()(0, last)) - mesh.restPositions().col(v);
  }
  simulation.setState(u, Eigen::VectorXd::Zero(mesh.numDofs()));
  try {
    simulation.step();
    ADD_FAILURE() << "no exception on rank " << worldRank();
  } catch (const NumericalError& error) {
    // The named element (in the mesh's numbering, whichever rank reports it) has one of
    // the moved vertices.
    const std::string message = error.what();
    std::smatch match;
    ASSERT_TRUE(std::regex_search(message, match, std::regex("^rank \\d+: .*element (\\d+) "))) << message;
    const int named = std::stoi(match[1].str());
    ASSERT_LT(named, mesh.numElements()) << message;
    bool touches = false;
    for (int a = 0; a < 4; ++a) {
      for (int b = 1; b < 4; ++b) touches = touches || mesh.elements()(a, named) == mesh.elements()(b, last);
    }
    EXPECT_TRUE(touches) << message;
  }
}

// A run restored from u, v, t and the internal state (a checkpoint: the trapezoidal
// acceleration) continues as the uninterrupted run: the same solves from the same state,
// different only in the last bit of the step times t_0 + k h (the direct tolerance).
// Without the acceleration it would restart from the equation of motion's a_0, which
// differs for the corotated tangent (asserted, so the restore is exercised).
TEST(PetscBackend, InternalStateContinuesTheRun) {
  const TetMesh mesh = beamMesh();
  const PetscSimulationSettings settings =
      beamSettings(mesh, PetscIntegratorKind::trapezoidal, PetscForceModelKind::corotational, PetscSolverKind::mumps);
  PetscSimulation whole(mesh, settings);
  for (int k = 0; k < 3; ++k) whole.step();
  Eigen::VectorXd u = whole.gatherDisplacement();
  Eigen::VectorXd v = whole.gatherVelocity();
  Eigen::VectorXd a = whole.gatherInternalState();
  const double t = whole.time();
  for (int k = 0; k < 3; ++k) whole.step();
  const Eigen::VectorXd expected = whole.gatherDisplacement();
  // Every rank restores the same full vectors (rank 0's, broadcast here).
  for (Eigen::VectorXd* vector : {&u, &v, &a}) {
    vector->resize(mesh.numDofs());
    MPI_Bcast(vector->data(), mesh.numDofs(), MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }
  const auto continued = [&](bool withAcceleration) {
    PetscSimulation resumed(mesh, settings);
    resumed.setState(u, v, t);
    resumed.setInternalState(withAcceleration ? a : Eigen::VectorXd());
    for (int k = 0; k < 3; ++k) resumed.step();
    return resumed.gatherDisplacement();
  };
  const Eigen::VectorXd restored = continued(true);
  const Eigen::VectorXd restarted = continued(false);
  PetscSimulation backwardEuler(mesh, beamSettings(mesh, PetscIntegratorKind::backwardEuler,
                                                   PetscForceModelKind::linear, PetscSolverKind::mumps));
  EXPECT_THROW(backwardEuler.setInternalState(a), ValidationError);
  EXPECT_EQ(backwardEuler.gatherInternalState().size(), 0);
  if (worldRank() != 0) return;
  const double scale = expected.lpNorm<Eigen::Infinity>();
  const double tolerance = comparisonTolerance(mesh, PetscSolverKind::mumps);
  EXPECT_LE((restored - expected).lpNorm<Eigen::Infinity>(), tolerance * scale);
  EXPECT_GT((restarted - expected).lpNorm<Eigen::Infinity>(), 10.0 * tolerance * scale);
}

// Partition agreement across separate runs: with ASYNCFEM_PETSC_TRAJECTORY_DIR set, each
// run (np = 1, 2, 3) stores its corotational trajectory; the ctest PetscBackend.PartitionsAgree
// then compares them (PetscPartitions.Agree, with ASYNCFEM_PETSC_COMPARE_DIR).
std::string trajectoryFile(const std::string& directory, int ranks, const std::string& tag = "") {
  return directory + "/petsc-trajectory" + tag + "-np" + std::to_string(ranks) + ".bin";
}

void storeTrajectory(const std::vector<Eigen::VectorXd>& displacements, const std::string& tag) {
  const char* directory = std::getenv("ASYNCFEM_PETSC_TRAJECTORY_DIR");
  if (worldRank() != 0 || directory == nullptr) return;
  std::ofstream out(trajectoryFile(directory, worldSize(), tag), std::ios::binary);
  for (const Eigen::VectorXd& u : displacements) {
    out.write(reinterpret_cast<const char*>(u.data()), static_cast<std::streamsize>(u.size() * sizeof(double)));
  }
  ASSERT_TRUE(out.good());
}

TEST(PetscPartitions, StoreTrajectory) {
  const TetMesh mesh = beamMesh();
  const PetscTrajectory trajectory = runPetscSimulation(
      mesh,
      beamSettings(mesh, PetscIntegratorKind::backwardEuler, PetscForceModelKind::corotational, PetscSolverKind::mumps),
      kSteps);
  storeTrajectory(trajectory.displacements, "");
  // Neo-Hookean with inversion handling under Newton and the line search (modelCase(2)).
  const ModelCase newton = modelCase(2);
  storeTrajectory(petscModelTrajectory(*modelProblem(newton), newton).displacements, "-newton");
}

std::vector<std::vector<Eigen::VectorXd>> readTrajectories(const std::string& directory, int numDofs, int steps,
                                                           const std::string& tag) {
  std::vector<std::vector<Eigen::VectorXd>> runs;
  for (int ranks : {1, 2, 3}) {
    std::ifstream in(trajectoryFile(directory, ranks, tag), std::ios::binary);
    EXPECT_TRUE(in.good()) << trajectoryFile(directory, ranks, tag);
    std::vector<Eigen::VectorXd> trajectory(static_cast<std::size_t>(steps), Eigen::VectorXd::Zero(numDofs));
    for (Eigen::VectorXd& u : trajectory) {
      in.read(reinterpret_cast<char*>(u.data()), static_cast<std::streamsize>(u.size() * sizeof(double)));
    }
    EXPECT_TRUE(in.good()) << "short file " << trajectoryFile(directory, ranks, tag);
    runs.push_back(std::move(trajectory));
  }
  return runs;
}

// Direct solves on 1, 2 and 3 ranks differ only by the rounding of differently ordered
// factorizations and sums: kappa * eps per step, the direct tolerance above. Newton runs
// may stop at different iterates: the Newton tolerance of modelTolerance().
TEST(PetscPartitions, Agree) {
  const char* directory = std::getenv("ASYNCFEM_PETSC_COMPARE_DIR");
  ASSERT_NE(directory, nullptr) << "run through ctest (PetscBackend.PartitionsAgree)";
  const TetMesh mesh = beamMesh();
  const std::vector<std::vector<Eigen::VectorXd>> runs = readTrajectories(directory, mesh.numDofs(), kSteps, "");
  const double tolerance = comparisonTolerance(mesh, PetscSolverKind::mumps);
  EXPECT_LE(trajectoryDifference(runs[1], runs[0]), tolerance) << "2 ranks vs 1";
  EXPECT_LE(trajectoryDifference(runs[2], runs[0]), tolerance) << "3 ranks vs 1";
  EXPECT_GT(runs[0].back().lpNorm<Eigen::Infinity>(), 1e-2);
  const std::vector<std::vector<Eigen::VectorXd>> newton =
      readTrajectories(directory, mesh.numDofs(), kModelSteps, "-newton");
  const double newtonTolerance = modelTolerance(mesh, modelCase(2));
  EXPECT_LE(trajectoryDifference(newton[1], newton[0]), newtonTolerance) << "Newton: 2 ranks vs 1";
  EXPECT_LE(trajectoryDifference(newton[2], newton[0]), newtonTolerance) << "Newton: 3 ranks vs 1";
  EXPECT_GT(newton[0].back().lpNorm<Eigen::Infinity>(), 1e-3);
}

}  // namespace
}  // namespace asyncfem::test

// PETSc is initialized once for all tests; only rank 0 prints gtest's report, and the
// exit status is the worst of all ranks, so a failure on any rank fails the ctest. When
// nothing failed but a test skipped, the status is 77, which ctest reports as skipped
// (SKIP_RETURN_CODE), so a skip never reads as a pass.
int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  int status = 1;
  {
    asyncfem::PetscRuntime runtime(&argc, &argv);
    if (runtime.rank() != 0) {
      delete ::testing::UnitTest::GetInstance()->listeners().Release(
          ::testing::UnitTest::GetInstance()->listeners().default_result_printer());
    }
    const int local[2] = {RUN_ALL_TESTS(), ::testing::UnitTest::GetInstance()->skipped_test_count()};
    int worst[2] = {1, 0};
    MPI_Allreduce(local, worst, 2, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    status = worst[0] != 0 ? worst[0] : (worst[1] > 0 ? 77 : 0);
  }
  return status;
}
