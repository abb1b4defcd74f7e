// SPDX-License-Identifier: BSD-3-Clause
// petscScaling: time per backward Euler step on a 3 x 1 x 1 box mesh (x = 0 face fixed,
// gravity, consistent mass) with the PETSc backend on the ranks mpiexec starts, or with
// the single-process CHOLMOD integrator (--solver cholmod, one rank). Prints one
// Markdown table row on rank 0 (times on rank 0 after a barrier, peak resident memory
// as the largest over the ranks); docs/petsc-backend.md collects the rows.
//
//   mpiexec -n 2 build/bin/petscScaling --cells 18 --steps 5 --solver cg-gamg
//   build/bin/petscScaling --cells 18 --steps 5 --solver cholmod
#include <mpi.h>
#include <sys/resource.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/hyperelasticFEM/isotropicHyperelasticFEM.hpp>
#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/petscBackend/petscRuntime.hpp>
#include <asyncfem/petscBackend/petscSimulation.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <thread>

#include "../benchmarkMachine.hpp"

namespace {

using asyncfem::bench::cpuModel;
using asyncfem::bench::loadAverage;

struct Options {
  int cells = 18;  // cells across the 1 x 1 section; 3 * cells along x
  int steps = 5;
  std::string solver = "cg-gamg";
  std::string model = "linear";                                   // linear, corotational, stvk or neo-hookean
  asyncfem::TangentKind tangent = asyncfem::TangentKind::simple;  // corotational only
  double timestep = 1e-3;
  bool header = false;
};

Options parse(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string key = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw asyncfem::ValidationError("petscScaling: " + key + " needs a value");
      return argv[++i];
    };
    if (key == "--cells") {
      options.cells = std::stoi(value());
    } else if (key == "--steps") {
      options.steps = std::stoi(value());
    } else if (key == "--solver") {
      options.solver = value();
    } else if (key == "--model") {
      options.model = value();
    } else if (key == "--tangent") {
      const std::string name = value();
      if (name != "simple" && name != "exact")
        throw asyncfem::ValidationError("petscScaling: --tangent simple|exact, got " + name);
      options.tangent = name == "exact" ? asyncfem::TangentKind::exact : asyncfem::TangentKind::simple;
    } else if (key == "--timestep") {
      options.timestep = std::stod(value());
    } else if (key == "--header") {
      options.header = true;
    } else if (key.rfind("-", 0) == 0 && key.rfind("--", 0) != 0) {
      // A PETSc option (-ksp_monitor, -pc_gamg_threshold 0.02, ...): PetscRuntime read it.
      if (i + 1 < argc && argv[i + 1][0] != '-') ++i;
    } else {
      throw asyncfem::ValidationError(
          "petscScaling: unknown argument " + key +
          " (--cells N --steps N --solver cg-gamg|cg-hypre|mumps|cholmod "
          "--model linear|corotational|stvk|neo-hookean --tangent simple|exact --timestep H "
          "--header)");
    }
  }
  if (options.cells < 1 || options.steps < 2)
    throw asyncfem::ValidationError("petscScaling: --cells >= 1, --steps >= 2");
  if (options.model != "linear" && options.model != "corotational" && options.model != "stvk" &&
      options.model != "neo-hookean")
    throw asyncfem::ValidationError("petscScaling: --model linear|corotational|stvk|neo-hookean, got " + options.model);
  return options;
}

asyncfem::TetMesh boxMesh(int cells) {
  asyncfem::BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(3.0, 1.0, 1.0);
  spec.cells = Eigen::Vector3i(3 * cells, cells, cells);
  spec.material = asyncfem::Material{"rubber", 1000.0, 1e6, 0.45};
  return asyncfem::makeBoxMesh(spec);
}

struct Row {
  int ranks = 1;
  long long freeDofs = 0;
  double setupSeconds = 0.0;      // build (partition, assembly; CHOLMOD: + factorization)
  double firstStepSeconds = 0.0;  // includes the preconditioner set-up / MUMPS factorization
  double stepSeconds = 0.0;       // mean of the later steps
  double iterationsPerStep = 0.0;
  double tipDisplacement = 0.0;  // |u|_inf after the last step, to compare the solvers' answers
};

Row runPetsc(const asyncfem::TetMesh& mesh, const Options& options) {
  asyncfem::PetscSimulationSettings settings;
  settings.forceModel = asyncfem::parsePetscForceModelKind(options.model);
  settings.tangent = options.tangent;
  settings.timestep = options.timestep;
  settings.fixedVertices = mesh.vertexSet("xmin");
  settings.gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  settings.solver.kind = asyncfem::parsePetscSolverKind(options.solver);
  settings.solver.relativeTolerance = 1e-8;
  Row row;
  MPI_Barrier(MPI_COMM_WORLD);
  asyncfem::Stopwatch watch;
  asyncfem::PetscSimulation simulation(mesh, settings);
  MPI_Barrier(MPI_COMM_WORLD);
  row.setupSeconds = watch.stop();
  watch.start();
  simulation.step();
  MPI_Barrier(MPI_COMM_WORLD);
  row.firstStepSeconds = watch.stop();
  const long long iterationsBefore = simulation.stats().solverIterations;
  watch.start();
  for (int k = 1; k < options.steps; ++k) simulation.step();
  MPI_Barrier(MPI_COMM_WORLD);
  row.stepSeconds = watch.stop() / (options.steps - 1);
  row.iterationsPerStep =
      static_cast<double>(simulation.stats().solverIterations - iterationsBefore) / (options.steps - 1);
  row.ranks = simulation.numRanks();
  row.freeDofs = simulation.stats().freeDofs;
  const Eigen::VectorXd u = simulation.gatherDisplacement();
  if (u.size() > 0) row.tipDisplacement = u.lpNorm<Eigen::Infinity>();
  return row;
}

Row runCholmod(const asyncfem::TetMesh& mesh, const Options& options) {
  Row row;
  asyncfem::Stopwatch watch;
  auto assembler = std::make_shared<const asyncfem::MatrixAssembler>(mesh);
  asyncfem::DynamicSystem system;
  if (options.model == "linear") {
    system.forceModel = std::make_shared<asyncfem::LinearForceModel>(asyncfem::linearStiffnessMatrix(mesh, *assembler));
  } else if (options.model == "corotational") {
    system.forceModel = std::make_shared<asyncfem::CorotationalLinearFEM>(mesh, assembler, options.tangent);
  } else {
    system.forceModel = std::make_shared<asyncfem::IsotropicHyperelasticFEM>(
        mesh, asyncfem::parseHyperelasticMaterialKind(options.model), asyncfem::HyperelasticOptions{}, assembler);
  }
  system.mass = asyncfem::massMatrix(mesh, *assembler, asyncfem::MassType::consistent);
  system.freeDofs = asyncfem::FreeDofs::fromFixedVertices(mesh.numVertices(), mesh.vertexSet("xmin"));
  const Eigen::VectorXd gravity = system.mass * Eigen::Vector3d(0.0, -9.81, 0.0).replicate(mesh.numVertices(), 1);
  system.externalForce = [gravity](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& forces) {
    forces += gravity;
  };
  asyncfem::BackwardEuler integrator(system, options.timestep);
  row.setupSeconds = watch.stop();
  watch.start();
  integrator.step();
  row.firstStepSeconds = watch.stop();
  watch.start();
  for (int k = 1; k < options.steps; ++k) integrator.step();
  row.stepSeconds = watch.stop() / (options.steps - 1);
  row.iterationsPerStep = 1.0;
  row.freeDofs = integrator.system().freeDofs.numFree();
  row.tipDisplacement = integrator.displacement().lpNorm<Eigen::Infinity>();
  return row;
}

/// The largest peak resident set size over the ranks, in MiB (Linux reports ru_maxrss in KiB).
double peakMemoryMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const long local = usage.ru_maxrss;
  long largest = local;
  MPI_Allreduce(&local, &largest, 1, MPI_LONG, MPI_MAX, MPI_COMM_WORLD);
  return static_cast<double>(largest) / 1024.0;
}

std::string modelName(const Options& options) {
  if (options.model != "corotational") return options.model;
  return options.tangent == asyncfem::TangentKind::exact ? "corotational (exact tangent)" : "corotational";
}

}  // namespace

int main(int argc, char** argv) {
  try {
    asyncfem::PetscRuntime runtime(&argc, &argv);
    const Options options = parse(argc, argv);
    if (options.solver == "cholmod" && runtime.size() != 1) {
      throw asyncfem::ValidationError("petscScaling: --solver cholmod runs on one rank");
    }
    const asyncfem::TetMesh mesh = boxMesh(options.cells);
    const Row row = options.solver == "cholmod" ? runCholmod(mesh, options) : runPetsc(mesh, options);
    const double memory = peakMemoryMiB();
    if (runtime.rank() == 0) {
      if (options.header) {
        std::printf("# %s, nproc %u, load %s\n", cpuModel().c_str(), std::thread::hardware_concurrency(),
                    loadAverage().c_str());
        std::printf(
            "| model | solver | ranks | tets | free DOFs | setup (s) | first step (s) | step (s) | "
            "iterations / step | peak MiB per rank | max abs u |\n"
            "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
      }
      std::printf("| %s | %s | %d | %d | %lld | %.2f | %.2f | %.3f | %.1f | %.0f | %.6e |\n",
                  modelName(options).c_str(), options.solver.c_str(), row.ranks, mesh.numElements(), row.freeDofs,
                  row.setupSeconds, row.firstStepSeconds, row.stepSeconds, row.iterationsPerStep, memory,
                  row.tipDisplacement);
      std::fflush(stdout);
    }
    return 0;
  } catch (const std::exception& error) {
    std::cerr << "petscScaling: " << error.what() << "\n";
    return 1;
  }
}
