// SPDX-License-Identifier: BSD-3-Clause
// The asynchronous integrator over MPI: L's system H^{LL*} solved distributed by PETSc
// (makePetscSparseSolver, makePetscLargeSystemSolver) against the single-process run, on
// 1, 2 and 3 ranks (the executable of petscBackendTest.cpp, run under mpiexec). Every test
// is collective.
#include <gtest/gtest.h>
#include <mpi.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/hexElements/hexCorotationalForceModel.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <asyncfem/petscBackend/largeSystemSolver.hpp>
#include <asyncfem/petscBackend/partition.hpp>
#include <asyncfem/petscBackend/rankSummedForceModel.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "../hexElements/hexBar.hpp"
#include "cantilever.hpp"

namespace asyncfem::test {
namespace {

constexpr double kStep = 0.02;
constexpr int kAsyncSteps = 12;
constexpr double kRelativeTolerance = 1e-10;  // of the iterative solves of L's system

/// Whether every rank holds exactly (bit for bit) the values rank 0 holds.
bool sameOnEveryRank(const Eigen::VectorXd& values) {
  Eigen::VectorXd root = values;
  MPI_Bcast(root.data(), static_cast<int>(root.size()), MPI_DOUBLE, 0, MPI_COMM_WORLD);
  int differs = std::memcmp(root.data(), values.data(), sizeof(double) * static_cast<std::size_t>(values.size())) != 0;
  int anyDiffers = 0;
  MPI_Allreduce(&differs, &anyDiffers, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return anyDiffers == 0;
}

TetMesh cantilever() { return rubberCantilever(); }

enum class Model { linear, corotational, neoHookean };

/// The cantilever under gravity with a sideways pull on its tip for the first 0.1 s.
DynamicSystem cantileverSystem(const std::shared_ptr<const TetMesh>& mesh, Model model) {
  auto assembler = std::make_shared<const MatrixAssembler>(*mesh);
  DynamicSystem system;
  if (model == Model::linear) {
    system.forceModel = std::make_shared<LinearForceModel>(linearStiffnessMatrix(*mesh, *assembler));
  } else if (model == Model::corotational) {
    system.forceModel = std::make_shared<CorotationalLinearFEM>(*mesh, assembler, TangentKind::exact);
  } else {
    system.forceModel = makeHyperelasticForceModel(*mesh, HyperelasticMaterialKind::neoHookean, {}, assembler);
  }
  system.mass = massMatrix(*mesh, *assembler, MassType::consistent);
  system.freeDofs = FreeDofs::fromFixedVertices(mesh->numVertices(), mesh->vertexSet("xmin"));
  system.mesh = mesh;
  const Eigen::VectorXd gravity = system.mass * Eigen::Vector3d(0.0, -9.81, 0.0).replicate(mesh->numVertices(), 1);
  const std::vector<int> tip = mesh->vertexSet("xmax");
  system.externalForce = [gravity, tip](double time, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                        Eigen::VectorXd& forces) {
    forces += gravity;
    if (time <= 0.1) {
      for (int v : tip) forces[(3 * v) + 2] += 2.0;
    }
  };
  return system;
}

/// The tip third of the cantilever steps at hL / 8.
std::vector<AsyncRegion> tipRegion(const TetMesh& mesh) {
  AsyncRegion region{"tip", {}, 8};
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).x() > 0.66) region.vertices.push_back(v);
  return {region};
}

/// The tip region and, apart from it, the vertices of the plane x = 0.25 at ratio 4.
std::vector<AsyncRegion> twoRegions(const TetMesh& mesh) {
  std::vector<AsyncRegion> regions = tipRegion(mesh);
  AsyncRegion plane{"plane", {}, 4};
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (std::abs(mesh.restPosition(v).x() - 0.25) < 1e-9) plane.vertices.push_back(v);
  regions.push_back(plane);
  return regions;
}

/// The problem settings of a nonlinear model as cantileverSystem() builds it.
ProblemSettings physicsOf(Model model) {
  ProblemSettings physics;
  physics.forceModel = model == Model::corotational ? ForceModelType::corotational : ForceModelType::neoHookean;
  physics.tangent = TangentKind::exact;
  return physics;
}

/// distributedElements: each rank evaluates its elements (makeRankSummedForceModel).
std::vector<Eigen::VectorXd> asyncTrajectory(Model model, const AsyncOptions& options, bool bothRegions = false,
                                             long long* factorizations = nullptr, bool distributedElements = false) {
  auto mesh = std::make_shared<const TetMesh>(cantilever());
  DynamicSystem system = cantileverSystem(mesh, model);
  if (distributedElements) system.forceModel = makeRankSummedForceModel(*mesh, physicsOf(model), system.forceModel);
  AsyncBackwardEuler integrator(*mesh, std::move(system), kStep, bothRegions ? twoRegions(*mesh) : tipRegion(*mesh),
                                options);
  std::vector<Eigen::VectorXd> states;
  for (int k = 0; k < kAsyncSteps; ++k) {
    integrator.step();
    states.push_back(integrator.displacement());
  }
  if (factorizations != nullptr) *factorizations = integrator.stats().factorizations;
  return states;
}

double largestDifference(const std::vector<Eigen::VectorXd>& a, const std::vector<Eigen::VectorXd>& b) {
  double difference = 0.0, scale = 0.0;
  for (std::size_t k = 0; k < b.size(); ++k) {
    difference = std::max(difference, (a[k] - b[k]).lpNorm<Eigen::Infinity>());
    scale = std::max(scale, b[k].lpNorm<Eigen::Infinity>());
  }
  return difference / scale;
}

/// M + h^2 K of the cantilever on its free DOFs, and the vertex of each row.
Eigen::SparseMatrix<double> freeSystem(const TetMesh& mesh, std::vector<int>& rowVertex) {
  MatrixAssembler assembler(mesh);
  const FreeDofs dofs = FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
  const Eigen::SparseMatrix<double> full =
      massMatrix(mesh, assembler, MassType::consistent) + (kStep * kStep) * linearStiffnessMatrix(mesh, assembler);
  const std::vector<int>& free = dofs.freeToFull();
  std::vector<int> position(static_cast<std::size_t>(full.rows()), -1);
  for (std::size_t k = 0; k < free.size(); ++k) position[static_cast<std::size_t>(free[k])] = static_cast<int>(k);
  std::vector<Eigen::Triplet<double>> entries;
  for (int c = 0; c < full.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(full, c); it; ++it) {
      const int row = position[static_cast<std::size_t>(it.row())], column = position[static_cast<std::size_t>(c)];
      if (row >= 0 && column >= 0) entries.emplace_back(row, column, it.value());
    }
  Eigen::SparseMatrix<double> system(static_cast<Eigen::Index>(free.size()), static_cast<Eigen::Index>(free.size()));
  system.setFromTriplets(entries.begin(), entries.end());
  system.makeCompressed();
  rowVertex.clear();
  for (int dof : free) rowVertex.push_back(dof / 3);
  return system;
}

// The distributed solve of a replicated SPD system equals a direct one: GAMG to a relative
// residual of 1e-10, so a relative error of at most kappa 1e-10 (kappa of M + h^2 K here is
// about 4.5e3: 1e-6 bounds it); MUMPS to rounding (1e-10). Every rank gets the same
// solution, bit for bit; a second factorization with new values solves the new system.
// solveApproximately: MUMPS solves exactly (rounding, 1e-10 of the solution); one GAMG cycle
// is a fixed linear map (approximate(b1 + 2 b2) = approximate(b1) + 2 approximate(b2) to
// rounding, 1e-10 relative) that at least halves the error's energy norm squared from a
// zero start, as the outer conjugate gradients of the lagged Schur refinement need; ranks
// agree bit for bit.
TEST(PetscSparseSolver, SolvesApproximatelyWithOneCycle) {
  const TetMesh mesh = cantilever();
  std::vector<int> rowVertex;
  const Eigen::SparseMatrix<double> system = freeSystem(mesh, rowVertex);
  Eigen::MatrixXd rhs(system.rows(), 3);
  for (Eigen::Index i = 0; i < rhs.rows(); ++i) {
    rhs(i, 0) = std::sin(0.37 * double(i));
    rhs(i, 1) = 1.0 + std::cos(0.11 * double(i));
  }
  rhs.col(2) = rhs.col(0) + 2.0 * rhs.col(1);
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  auto owner = std::make_shared<std::vector<int>>(static_cast<std::size_t>(mesh.numVertices()));
  for (int v = 0; v < mesh.numVertices(); ++v) (*owner)[static_cast<std::size_t>(v)] = v % ranks;
  auto coordinates = std::make_shared<const Eigen::Matrix3Xd>(mesh.restPositions());
  for (PetscSolverKind kind : {PetscSolverKind::cgGamg, PetscSolverKind::mumps}) {
    SCOPED_TRACE(kind == PetscSolverKind::mumps ? "MUMPS" : "CG + GAMG");
    PetscSolverSettings settings;
    settings.kind = kind;
    settings.relativeTolerance = kRelativeTolerance;
    std::unique_ptr<SparseSolver> solver = makePetscSparseSolver(settings, rowVertex, owner, coordinates);
    solver->compute(system);
    Eigen::MatrixXd approximate, exact;
    solver->solveApproximately(rhs, approximate);
    solver->solve(rhs, exact);
    const Eigen::VectorXd combined = approximate.col(0) + 2.0 * approximate.col(1);
    EXPECT_LE((approximate.col(2) - combined).norm(), 1e-10 * combined.norm());
    for (int j = 0; j < 2; ++j) {
      // The error shrinks in the energy norm (the norm conjugate gradients minimize in).
      const Eigen::VectorXd error = exact.col(j) - approximate.col(j);
      EXPECT_LT(error.dot(system * error), 0.5 * exact.col(j).dot(system * exact.col(j)));
      if (kind == PetscSolverKind::mumps) {
        EXPECT_LE((approximate.col(j) - exact.col(j)).norm(), 1e-10 * exact.col(j).norm());
      } else {
        EXPECT_GT((approximate.col(j) - exact.col(j)).norm(), 1e-6 * exact.col(j).norm());  // one cycle, not a solve
      }
      EXPECT_TRUE(sameOnEveryRank(approximate.col(j)));
    }
  }
}

TEST(PetscSparseSolver, SolvesLikeADirectSolverOnEveryRank) {
  const TetMesh mesh = cantilever();
  std::vector<int> rowVertex;
  Eigen::SparseMatrix<double> system = freeSystem(mesh, rowVertex);
  Eigen::MatrixXd rhs(system.rows(), 2);
  for (Eigen::Index i = 0; i < rhs.rows(); ++i) {
    rhs(i, 0) = std::sin(0.37 * double(i));
    rhs(i, 1) = 1.0 + std::cos(0.11 * double(i));
  }
  auto owner = std::make_shared<std::vector<int>>(static_cast<std::size_t>(mesh.numVertices()));
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  for (int v = 0; v < mesh.numVertices(); ++v) (*owner)[static_cast<std::size_t>(v)] = v % ranks;
  auto coordinates = std::make_shared<const Eigen::Matrix3Xd>(mesh.restPositions());
  for (PetscSolverKind kind : {PetscSolverKind::cgGamg, PetscSolverKind::mumps}) {
    PetscSolverSettings settings;
    settings.kind = kind;
    settings.relativeTolerance = kRelativeTolerance;
    const double tolerance = kind == PetscSolverKind::mumps ? 1e-10 : 1e-6;
    auto totals = std::make_shared<PetscSolveCounts>();
    std::unique_ptr<SparseSolver> solver = makePetscSparseSolver(settings, rowVertex, owner, coordinates, totals);
    EXPECT_EQ(solver->kind(), SolverKind::external);
    EXPECT_THROW(solver->solve(rhs.col(0).eval()), Error);  // before any factorization
    for (double scale : {1.0, 3.0}) {
      const Eigen::SparseMatrix<double> scaled = scale * system;
      if (scale == 1.0) solver->analyzePattern(scaled);
      solver->factorize(scaled);
      Eigen::MatrixXd x;
      solver->solve(rhs, x);
      const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> direct(scaled);
      const Eigen::MatrixXd exact = direct.solve(rhs);
      EXPECT_LE((x - exact).norm(), tolerance * exact.norm()) << toString(kind) << " scale " << scale;
      EXPECT_TRUE(sameOnEveryRank(Eigen::Map<const Eigen::VectorXd>(x.data(), x.size())));
    }
    EXPECT_EQ(totals->solves, 4);
    // An iterative solver asks for a preconditioning matrix and builds its multigrid on it:
    // on the diagonal of A alone it still converges to the same solution, in more iterations.
    EXPECT_EQ(solver->usesPreconditionerMatrix(), kind != PetscSolverKind::mumps);
    if (solver->usesPreconditionerMatrix()) {
      const long long before = totals->iterations;
      const Eigen::VectorXd entries = system.diagonal();
      std::vector<Eigen::Triplet<double>> triplets;
      for (Eigen::Index r = 0; r < entries.size(); ++r) triplets.emplace_back(r, r, entries[r]);
      Eigen::SparseMatrix<double> diagonal(system.rows(), system.cols());
      diagonal.setFromTriplets(triplets.begin(), triplets.end());
      diagonal.makeCompressed();
      solver->setPreconditionerMatrix(diagonal);
      solver->factorize(system);
      Eigen::MatrixXd x;
      solver->solve(rhs, x);
      const Eigen::MatrixXd exact = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(system).solve(rhs);
      EXPECT_LE((x - exact).norm(), tolerance * exact.norm());
      EXPECT_GT(totals->iterations - before, 2 * before / 4) << "the preconditioning matrix was not used";
    }
    EXPECT_GT(totals->ownedRows, 0);
    Eigen::SparseMatrix<double> other = system;
    other.coeffRef(0, other.cols() - 1) = 1.0;  // a new entry (the beam's far ends): another pattern
    other.makeCompressed();
    EXPECT_THROW(solver->factorize(other), Error);
  }
}

struct AsyncCase {
  Model model;
  PetscSolverKind solver;
};

class PetscAsync : public ::testing::TestWithParam<AsyncCase> {};

// The asynchronous run with L's system on PETSc follows the single-process run (CHOLMOD) to
// the solver's tolerance: each large step's Y carries a relative error of at most kappa
// 1e-10 (GAMG; kappa of H^{LL*} is at most that of M + hL^2 K, ~4.5e3), the regions'
// recoveries inherit it at the interface, and 10x covers the accumulation over the run
// (as in PetscVersusCholmod): 5e-6; MUMPS: rounding, kappa 1e-15 per step, 1e-10. The
// nonlinear models keep the lagged H^{LL*} (the distributed solve is its preconditioner).
// Every rank steps the same state: the trajectories agree bit for bit across ranks.
TEST_P(PetscAsync, TrajectoryMatchesTheLocalAsyncRun) {
  const AsyncCase c = GetParam();
  const std::vector<Eigen::VectorXd> local = asyncTrajectory(c.model, AsyncOptions{});
  auto mesh = std::make_shared<const TetMesh>(cantilever());
  PetscSolverSettings settings;
  settings.kind = c.solver;
  settings.relativeTolerance = kRelativeTolerance;
  auto totals = std::make_shared<PetscSolveCounts>();
  AsyncOptions options;
  options.processes.largeSystemSolver = makePetscLargeSystemSolver(*mesh, settings, totals);
  const std::vector<Eigen::VectorXd> distributed = asyncTrajectory(c.model, options);
  const double tolerance = c.solver == PetscSolverKind::mumps ? 1e-10 : 5e-6;
  EXPECT_LE(largestDifference(distributed, local), tolerance);
  EXPECT_GT(local.back().lpNorm<Eigen::Infinity>(), 1e-3);  // the beam moves
  EXPECT_GE(totals->solves, kAsyncSteps);                   // L was solved on PETSc
  EXPECT_TRUE(sameOnEveryRank(distributed.back()));
  // The tip region's interface (one layer of vertices) is far below a rank's share of L's:
  // one rank owns all of its rows.
  EXPECT_EQ(totals->regionsOnOneRank, 1);
  EXPECT_EQ(totals->regionsSplit, 0);
}

std::string asyncCaseName(const ::testing::TestParamInfo<AsyncCase>& info) {
  const char* models[] = {"linear", "corotational", "neoHookean"};
  return std::string(models[static_cast<int>(info.param.model)]) + "_" +
         (info.param.solver == PetscSolverKind::mumps ? "mumps" : "gamg");
}

INSTANTIATE_TEST_SUITE_P(Models, PetscAsync,
                         ::testing::Values(AsyncCase{Model::linear, PetscSolverKind::cgGamg},
                                           AsyncCase{Model::linear, PetscSolverKind::mumps},
                                           AsyncCase{Model::corotational, PetscSolverKind::cgGamg},
                                           AsyncCase{Model::neoHookean, PetscSolverKind::mumps}),
                         asyncCaseName);

// AsyncOptions::Processes::regionDistribution from makePetscRegionDistribution: each of two regions is
// computed by one rank only (its A^S, Z, C_i, substitutions and recovery), the rest summed
// with MPI_Allreduce. The trajectory follows the local run to the same tolerances as the
// replicated regions (the sums add the owner's values to zeros, so they are exact; the rest
// is the L solve's tolerance), every rank holds the same state, and a rank that owns fewer
// than both regions factors less than the local run.
TEST(PetscAsync, RegionsOwnedByOneRankFollowTheLocalRun) {
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  for (const AsyncCase c :
       {AsyncCase{Model::linear, PetscSolverKind::mumps}, AsyncCase{Model::corotational, PetscSolverKind::cgGamg}}) {
    SCOPED_TRACE(c.model == Model::linear ? "linear, MUMPS" : "corotational, GAMG");
    long long localFactorizations = 0, factorizations = 0;
    const std::vector<Eigen::VectorXd> local = asyncTrajectory(c.model, AsyncOptions{}, true, &localFactorizations);
    auto mesh = std::make_shared<const TetMesh>(cantilever());
    PetscSolverSettings settings;
    settings.kind = c.solver;
    settings.relativeTolerance = kRelativeTolerance;
    AsyncOptions options;
    options.processes.largeSystemSolver = makePetscLargeSystemSolver(*mesh, settings);
    const PetscRegionDistribution distribution = makePetscRegionDistribution(*mesh);
    options.processes.regionDistribution.ownedRegions = distribution.ownedRegions;
    options.processes.regionDistribution.sum = distribution.sum;
    const std::vector<Eigen::VectorXd> distributed = asyncTrajectory(c.model, options, true, &factorizations);
    EXPECT_LE(largestDifference(distributed, local), c.solver == PetscSolverKind::mumps ? 1e-10 : 5e-6);
    EXPECT_TRUE(sameOnEveryRank(distributed.back()));
    // How many regions this rank computes, from the distribution itself.
    const RegionPartition partition(*mesh, cantileverSystem(mesh, c.model).freeDofs, twoRegions(*mesh));
    std::vector<std::vector<int>> regionDofs, interfaceDofs;
    for (int i = 0; i < partition.numRegions(); ++i) {
      regionDofs.push_back(partition.regionDofs(i));
      interfaceDofs.push_back(partition.interfaceDofs(i));
    }
    const std::vector<char> owned = distribution.ownedRegions(regionDofs, interfaceDofs);
    int mine = static_cast<int>(std::count(owned.begin(), owned.end(), 1)), total = 0;
    MPI_Allreduce(&mine, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
    EXPECT_EQ(total, 2);
    if (mine < 2) {
      EXPECT_LT(factorizations, localFactorizations);
    }
    if (ranks == 1) {
      EXPECT_EQ(mine, 2);
    }
  }
}

// regionOwners: a region whose interface lies on one rank goes to that rank; one without
// an interface (or with a split one) to the rank owning most of its vertices.
TEST(AssignVertexOwners, RegionOwnersFollowTheirInterface) {
  const TetMesh mesh = cantilever();
  std::vector<int> parts(static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) {
    double x = 0.0;
    for (const int v : mesh.element(e)) x += mesh.restPosition(v).x() / 4.0;
    parts[static_cast<std::size_t>(e)] = x < 0.5 ? 0 : 1;
  }
  // Region 0: the plane x = 7/12 (lowest-part owner 1) with the interface planes 5/12, 1/2
  // (owner 0) and 2/3 (owner 1): the interface goes whole to rank 0, and the region with
  // it. Region 1: the plane x = 5/6, interface planes 3/4 and 11/12 (all on rank 1). Region
  // 2: no interface, the planes 5/12, 1/2 and 7/12 (2 of 3 on rank 0).
  const auto planes = [&mesh](std::initializer_list<double> xs) {
    std::vector<int> out;
    for (int v = 0; v < mesh.numVertices(); ++v)
      for (const double x : xs)
        if (std::abs(mesh.restPosition(v).x() - x) < 1e-9) out.push_back(v);
    return out;
  };
  const std::vector<std::vector<int>> regions{planes({7.0 / 12}), planes({5.0 / 6}), planes({5.0 / 12, 0.5, 7.0 / 12})};
  const std::vector<std::vector<int>> interfaces{planes({5.0 / 12, 0.5, 2.0 / 3}), planes({0.75, 11.0 / 12}), {}};
  EXPECT_EQ(regionOwners(mesh, parts, 2, regions, interfaces, 1000), (std::vector<int>{0, 1, 0}));
  // With a limit below the interfaces' sizes they stay split (region 1's lies on one rank
  // anyway), and region 0 goes by its own vertices: rank 1.
  EXPECT_EQ(regionOwners(mesh, parts, 2, regions, interfaces, 4), (std::vector<int>{1, 1, 0}));
}

// assignVertexOwners: every vertex outside the groups keeps the lowest part among its
// elements'; each group (merged with those it shares a vertex with) moves whole to the rank
// that owned most of it; a group over the size limit is left as it was. Exact integers, so
// compared exactly; the expected owners are computed here from the definitions.
TEST(AssignVertexOwners, KeepsEachInterfaceOnTheRankThatHeldMostOfIt) {
  const TetMesh mesh = cantilever();
  const int ranks = 3;
  std::vector<int> parts(static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) {
    double x = 0.0;
    for (const int v : mesh.element(e)) x += mesh.restPosition(v).x() / 4.0;
    parts[static_cast<std::size_t>(e)] = std::min(2, static_cast<int>(x * 3.0));
  }
  std::vector<int> lowest(static_cast<std::size_t>(mesh.numVertices()), ranks);
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (const int v : mesh.element(e)) {
      lowest[static_cast<std::size_t>(v)] =
          std::min(lowest[static_cast<std::size_t>(v)], parts[static_cast<std::size_t>(e)]);
    }
  }
  // Group 0 straddles the cut at x = 1/3 (more of it on part 0); groups 1 and 2 share a
  // vertex near x = 2/3 and are merged (more of them on part 2); group 3 is too large.
  std::vector<std::vector<int>> groups(4);
  int sharedVertex = -1;
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const double x = mesh.restPosition(v).x();
    if (x > 0.2 && x < 0.45) groups[0].push_back(v);
    if (x > 0.6 && x < 0.68) groups[1].push_back(v);
    if (x > 0.66 && x < 0.9) groups[2].push_back(v);
    if (x > 0.6 && x < 0.68 && x > 0.66) sharedVertex = v;
    if (x > 0.9) groups[3].push_back(v);
  }
  ASSERT_GE(sharedVertex, 0);
  const int limit = static_cast<int>(groups[3].size()) - 1;
  const VertexOwners owners = assignVertexOwners(mesh, parts, ranks, groups, 1000);
  const VertexOwners limited = assignVertexOwners(mesh, parts, ranks, {groups[3]}, limit);
  EXPECT_EQ(owners.groupsKept, 3);  // 0, {1, 2} and 3 under the limit of 1000
  EXPECT_EQ(owners.groupsSplit, 0);
  EXPECT_EQ(limited.groupsKept, 0);
  EXPECT_EQ(limited.groupsSplit, 1);
  EXPECT_EQ(limited.owner, lowest);  // the split group keeps the lowest-part owners
  const auto majority = [&lowest, ranks](const std::vector<int>& vertices) {
    std::vector<int> votes(static_cast<std::size_t>(ranks), 0);
    for (const int v : vertices) ++votes[static_cast<std::size_t>(lowest[static_cast<std::size_t>(v)])];
    return static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  };
  std::vector<int> merged = groups[1];
  merged.insert(merged.end(), groups[2].begin(), groups[2].end());
  std::sort(merged.begin(), merged.end());
  merged.erase(std::unique(merged.begin(), merged.end()), merged.end());
  std::vector<int> expected = lowest;
  for (const std::vector<int>* group : {&groups[0], &merged, &groups[3]}) {
    const int keeper = majority(*group);
    for (const int v : *group) expected[static_cast<std::size_t>(v)] = keeper;
  }
  EXPECT_EQ(owners.owner, expected);
  // The straddling group had vertices on two parts before and has one now.
  std::vector<int> before, after;
  for (const int v : groups[0]) {
    before.push_back(lowest[static_cast<std::size_t>(v)]);
    after.push_back(owners.owner[static_cast<std::size_t>(v)]);
  }
  EXPECT_NE(*std::min_element(before.begin(), before.end()), *std::max_element(before.begin(), before.end()));
  EXPECT_EQ(*std::min_element(after.begin(), after.end()), *std::max_element(after.begin(), after.end()));
  // A vertex id outside the mesh is named.
  try {
    assignVertexOwners(mesh, parts, ranks, {{0, mesh.numVertices()}}, 1000);
    ADD_FAILURE() << "an out-of-range vertex was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("vertex " + std::to_string(mesh.numVertices())), std::string::npos)
        << error.what();
  }
}

// The paper's coupling (an unsymmetric H^{LL*}) and the naive method are refused by name.
TEST(PetscAsync, OnlyTheStableStructuredSolveTakesAnExternalSolver) {
  auto mesh = std::make_shared<const TetMesh>(cantilever());
  AsyncOptions options;
  options.processes.largeSystemSolver = makePetscLargeSystemSolver(*mesh, PetscSolverSettings{});
  options.coupling = AsyncCoupling::paper;
  try {
    AsyncBackwardEuler integrator(*mesh, cantileverSystem(mesh, Model::linear), kStep, tipRegion(*mesh), options);
    ADD_FAILURE() << "the paper's coupling was accepted";
  } catch (const ValidationError& error) {
    EXPECT_NE(std::string(error.what()).find("stable coupling"), std::string::npos) << error.what();
  }
  options.coupling = AsyncCoupling::stable;
  options.method = AsyncSolveMethod::naive;
  EXPECT_THROW(AsyncBackwardEuler(*mesh, cantileverSystem(mesh, Model::linear), kStep, tipRegion(*mesh), options),
               ValidationError);
}

// makeRankSummedForceModel: each rank's elements through the sub-mesh model, summed over the
// ranks, give the whole-mesh model's forces and tangent up to the order of the element sums:
// each entry sums at most 24 element contributions (a vertex's tets), so the difference is
// a few ulps of the largest entry; 1e-12 of the largest entry bounds it with a wide margin.
// Every rank receives the same values, bit for bit; a wrong-size stiffness gets the pattern.
// (On one rank the model is the whole-mesh model itself.)
TEST(RankSummedForceModel, EqualsTheWholeMeshModel) {
  auto mesh = std::make_shared<const TetMesh>(cantilever());
  auto assembler = std::make_shared<const MatrixAssembler>(*mesh);
  Eigen::VectorXd u(mesh->numDofs());
  for (int v = 0; v < mesh->numVertices(); ++v) {  // a bend with a twist: large rotations
    const Eigen::Vector3d x = mesh->restPosition(v);
    u.segment<3>(3 * v) = Eigen::Vector3d(0.02 * std::sin(3.0 * x.y()), -0.3 * x.x() * x.x(), 0.1 * x.x() * x.y());
  }
  for (const ForceModelType type :
       {ForceModelType::corotational, ForceModelType::stvk, ForceModelType::neoHookean, ForceModelType::mooneyRivlin}) {
    SCOPED_TRACE(toString(type));
    ProblemSettings physics;
    physics.forceModel = type;
    physics.tangent = TangentKind::exact;
    // The options reach the sub-mesh models (StVK keeps its Green-strain form, which has none).
    if (type != ForceModelType::stvk) physics.hyperelastic.inversionThreshold = 0.3;
    if (type == ForceModelType::mooneyRivlin) physics.hyperelastic.mooneyRivlin = MooneyRivlinParameters{5e4, 2e5, 1e6};
    std::shared_ptr<ForceModel> whole;
    if (type == ForceModelType::corotational) {
      whole = std::make_shared<CorotationalLinearFEM>(*mesh, assembler, TangentKind::exact);
    } else {
      const HyperelasticMaterialKind kind = type == ForceModelType::stvk ? HyperelasticMaterialKind::stvk
                                            : type == ForceModelType::neoHookean
                                                ? HyperelasticMaterialKind::neoHookean
                                                : HyperelasticMaterialKind::mooneyRivlin;
      whole = makeHyperelasticForceModel(*mesh, kind, physics.hyperelastic, assembler);
    }
    const std::shared_ptr<ForceModel> summed = makeRankSummedForceModel(*mesh, physics, whole);
    Eigen::VectorXd expectedForces, forces;
    Eigen::SparseMatrix<double> expected = whole->createStiffnessMatrix(), tangent;  // tangent: empty, wrong size
    whole->forcesAndTangent(u, expectedForces, expected);
    summed->forcesAndTangent(u, forces, tangent);
    ASSERT_EQ(tangent.nonZeros(), expected.nonZeros());
    const Eigen::Map<const Eigen::VectorXd> values(tangent.valuePtr(), tangent.nonZeros());
    const Eigen::Map<const Eigen::VectorXd> expectedValues(expected.valuePtr(), expected.nonZeros());
    EXPECT_LE((forces - expectedForces).lpNorm<Eigen::Infinity>(), 1e-12 * expectedForces.lpNorm<Eigen::Infinity>());
    EXPECT_LE((values - expectedValues).lpNorm<Eigen::Infinity>(), 1e-12 * expectedValues.lpNorm<Eigen::Infinity>());
    EXPECT_GT(expectedForces.lpNorm<Eigen::Infinity>(), 0.0);
    EXPECT_TRUE(sameOnEveryRank(forces));
    EXPECT_TRUE(sameOnEveryRank(values));
    // The other members are the whole-mesh model's, evaluated on this rank alone.
    EXPECT_EQ(summed->elasticEnergy(u), whole->elasticEnergy(u));
    EXPECT_EQ(summed->isLinear(), false);
  }
  ProblemSettings linear;
  EXPECT_THROW(makeRankSummedForceModel(*mesh, linear,
                                        std::make_shared<LinearForceModel>(linearStiffnessMatrix(*mesh, *assembler))),
               ValidationError);
}

// An element whose forces are not finite on one rank (a vertex of the last rank's part
// with a NaN displacement, as a blown-up state has) stops every rank with the same
// NumericalError, naming an element of the mesh (not of the rank's sub-mesh) that holds
// the vertex; afterwards the ranks are still in step.
TEST(RankSummedForceModel, AnElementFailingOnOneRankStopsEveryRank) {
  auto mesh = std::make_shared<const TetMesh>(cantilever());
  auto assembler = std::make_shared<const MatrixAssembler>(*mesh);
  ProblemSettings physics = physicsOf(Model::neoHookean);
  const std::shared_ptr<ForceModel> summed = makeRankSummedForceModel(
      *mesh, physics, makeHyperelasticForceModel(*mesh, HyperelasticMaterialKind::neoHookean, {}, assembler));
  int ranks = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  const std::vector<int> parts = partitionElements(*mesh, ranks);
  const int element = static_cast<int>(std::find(parts.begin(), parts.end(), ranks - 1) - parts.begin());
  const int vertex = mesh->elements()(0, element);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh->numDofs());
  u[3 * vertex] = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd forces;
  Eigen::SparseMatrix<double> tangent = summed->createStiffnessMatrix();
  try {
    summed->forcesAndTangent(u, forces, tangent);
    ADD_FAILURE() << "a non-finite element went through";
  } catch (const NumericalError& error) {
    std::smatch named;
    const std::string message = error.what();
    ASSERT_TRUE(std::regex_search(message, named, std::regex("element (\\d+)"))) << message;
    const int failed = std::stoi(named[1].str());
    ASSERT_LT(failed, mesh->numElements()) << message;
    bool holdsVertex = false;
    for (int a = 0; a < 4; ++a) holdsVertex = holdsVertex || mesh->elements()(a, failed) == vertex;
    EXPECT_TRUE(holdsVertex) << message;
    if (ranks > 1) {  // on one rank the model is the whole-mesh one, whose message has no rank
      EXPECT_EQ(message.rfind("rank ", 0), 0U) << message;
    }
  }
  // The ranks are still in step: a collective call completes.
  int one = 1, sum = 0;
  MPI_Allreduce(&one, &sum, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(sum, ranks);
}

// The asynchronous run with every rank evaluating only its elements (and each region
// computed by its owner, L on MUMPS) follows the local run to 1e-10 as the replicated one
// does: the element sums differ from the local run's by round-off only (kappa 1e-15 per step
// through the solve), and every rank holds the same state.
TEST(PetscAsync, DistributedElementLoopsFollowTheLocalRun) {
  for (const Model model : {Model::corotational, Model::neoHookean}) {
    SCOPED_TRACE(model == Model::corotational ? "corotational" : "neo-Hookean");
    const std::vector<Eigen::VectorXd> local = asyncTrajectory(model, AsyncOptions{}, true);
    auto mesh = std::make_shared<const TetMesh>(cantilever());
    PetscSolverSettings settings;
    settings.kind = PetscSolverKind::mumps;
    AsyncOptions options;
    options.processes.largeSystemSolver = makePetscLargeSystemSolver(*mesh, settings);
    const PetscRegionDistribution distribution = makePetscRegionDistribution(*mesh);
    options.processes.regionDistribution.ownedRegions = distribution.ownedRegions;
    options.processes.regionDistribution.sum = distribution.sum;
    const std::vector<Eigen::VectorXd> distributed = asyncTrajectory(model, options, true, nullptr, true);
    EXPECT_LE(largestDifference(distributed, local), 1e-10);
    EXPECT_GT(local.back().lpNorm<Eigen::Infinity>(), 1e-3);
    EXPECT_TRUE(sameOnEveryRank(distributed.back()));
  }
}

// A hexahedral cantilever (8 x 2 x 2 cubes, corotational FEM with the derivative of R K v)
// stepped asynchronously with its tip cubes at hL / 4, every rank evaluating its own
// elements (makeRankSummedForceModel, whose element tangents the stable coupling asks for in
// 24 x 24) and L's system on MUMPS: the trajectory equals the single-process run to rounding
// (1e-10, as the tetrahedral MUMPS cases) and is the same on every rank.
TEST(PetscAsyncHexahedra, CantileverMatchesTheLocalRun) {
  auto mesh = std::make_shared<const TetMesh>(test::hexBar(2));
  std::vector<int> fixed;
  AsyncRegion tip{"tip", {}, 4};
  for (int v = 0; v < mesh->numVertices(); ++v) {
    if (mesh->restPosition(v).x() == 0.0) fixed.push_back(v);
    if (mesh->restPosition(v).x() > 0.74) tip.vertices.push_back(v);
  }
  ProblemSettings physics;
  physics.forceModel = ForceModelType::corotational;
  physics.tangent = TangentKind::exact;
  const auto run = [&](bool distributed) {
    DynamicSystem system;
    system.forceModel = std::make_shared<HexCorotationalForceModel>(*mesh, false);
    if (distributed) system.forceModel = makeRankSummedForceModel(*mesh, physics, system.forceModel);
    system.mass = hexMassMatrix(*mesh, MassType::consistent);
    system.freeDofs = FreeDofs::fromFixedVertices(mesh->numVertices(), fixed);
    system.mesh = mesh;
    const Eigen::VectorXd gravity = system.mass * Eigen::Vector3d(0.0, -9.81, 0.0).replicate(mesh->numVertices(), 1);
    system.externalForce = [gravity](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& forces) {
      forces += gravity;
    };
    AsyncOptions options;
    if (distributed) {
      PetscSolverSettings settings;
      settings.kind = PetscSolverKind::mumps;
      options.processes.largeSystemSolver = makePetscLargeSystemSolver(*mesh, settings);
    }
    AsyncBackwardEuler integrator(*mesh, std::move(system), kStep, {tip}, options);
    std::vector<Eigen::VectorXd> states;
    for (int k = 0; k < kAsyncSteps; ++k) {
      integrator.step();
      states.push_back(integrator.displacement());
    }
    return states;
  };
  const std::vector<Eigen::VectorXd> local = run(false);
  const std::vector<Eigen::VectorXd> distributed = run(true);
  EXPECT_GT(local.back().lpNorm<Eigen::Infinity>(), 1e-3);  // the beam sags
  EXPECT_LE(largestDifference(distributed, local), 1e-10);
  EXPECT_TRUE(sameOnEveryRank(distributed.back()));
}

}  // namespace
}  // namespace asyncfem::test
