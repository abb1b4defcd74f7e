// SPDX-License-Identifier: BSD-3-Clause
// Cost of warping one frame against one linear backward Euler step on the same mesh
// (Zhao, Li & Barbič 2016 report warping at about 40-60% of a step). Printed as a
// Markdown table; every time is a median of per-call wall times after warm-up calls, and
// every ratio compares two measurements of the same run.
//
//   benchmarkWarping [--cells 20,40,80] [--repeats 30]
//
// Meshes: makeBeamMesh cantilevers (length 1, 0.2 x 0.2 section, root fixed) with the
// given cells along the length; the displacement warped is the integrator's state after
// the warm-up steps of a tip pull (a realistic bending field).
#include <omp.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/warping/modalWarping.hpp>
#include <asyncfem/warping/rotationStrainWarping.hpp>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "../benchmarkMachine.hpp"

namespace {

using asyncfem::bench::cpuModel;
using asyncfem::bench::loadAverage;

using namespace asyncfem;

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

/// Median seconds of call() over repeats calls after two untimed ones.
double medianSeconds(const std::function<void()>& call, int repeats) {
  call();
  call();
  std::vector<double> samples;
  for (int k = 0; k < repeats; ++k) {
    Stopwatch watch;
    watch.start();
    call();
    samples.push_back(watch.stop());
  }
  return median(samples);
}

struct Row {
  int vertices = 0;
  int elements = 0;
  double stepSeconds = 0.0;
  double rotationStrainSetup = 0.0;
  double rotationStrainSeconds = 0.0;
  double modalSetup = 0.0;
  double modalSeconds = 0.0;
  long long laplacianFactorNonZeros = 0;
  double maxRotation = 0.0;
};

Row measure(int cellsAlongLength, int repeats) {
  BeamSpec spec;
  spec.cellsAlongLength = cellsAlongLength;
  const TetMesh mesh = makeBeamMesh(spec);
  const MatrixAssembler assembler(mesh);
  DynamicSystem system;
  system.forceModel = std::make_shared<LinearForceModel>(linearStiffnessMatrix(mesh, assembler));
  system.mass = massMatrix(mesh, assembler, MassType::consistent);
  const std::vector<int>& root = mesh.vertexSet("root");
  system.freeDofs = FreeDofs::fromFixedVertices(mesh.numVertices(), root);
  const std::vector<int> tip = mesh.vertexSet("tip");
  system.externalForce = [tip](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (const int v : tip) {
      f[(3 * v) + 1] -= 0.5;
    }
  };
  auto integrator = makeIntegrator("backward-euler", system, 1.0 / 600.0);

  Row row;
  row.vertices = mesh.numVertices();
  row.elements = mesh.numElements();
  for (int k = 0; k < 20; ++k) {
    integrator->step();  // the first step factors M + h^2 K once
  }
  row.stepSeconds = medianSeconds([&] { integrator->step(); }, repeats);
  const Eigen::VectorXd displacement = integrator->displacement();

  Stopwatch setup;
  setup.start();
  RotationStrainWarping rotationStrain(mesh, root);
  row.rotationStrainSetup = setup.stop();
  row.laplacianFactorNonZeros = rotationStrain.solverStats().factorNonZeros;
  row.rotationStrainSeconds = medianSeconds([&] { rotationStrain.warp(displacement); }, repeats);

  setup.reset();
  setup.start();
  ModalWarping modal(mesh);
  row.modalSetup = setup.stop();
  row.modalSeconds = medianSeconds([&] { modal.warp(displacement); }, repeats);

  const Eigen::VectorXd w = modal.rotationVectors(displacement);
  for (int v = 0; v < mesh.numVertices(); ++v) {
    row.maxRotation = std::max(row.maxRotation, w.segment<3>(3 * v).norm());
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Warping time per frame against one linear backward Euler step on the same mesh."};
  std::vector<int> cells{20, 40, 80};
  int repeats = 30;
  app.add_option("--cells", cells, "Cells along the beam's length, one mesh each")->delimiter(',');
  app.add_option("--repeats", repeats, "Timed calls per measurement (median)")->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);

  std::printf("## Warping per frame vs one linear backward Euler step\n\n");
  std::printf("Machine: %s, %u hardware threads, %d OpenMP threads. Command: benchmarkWarping --cells",
              cpuModel().c_str(), std::thread::hardware_concurrency(), omp_get_max_threads());
  for (std::size_t k = 0; k < cells.size(); ++k) {
    std::printf("%s%d", k == 0 ? " " : ",", cells[k]);
  }
  std::printf(" --repeats %d\n\n", repeats);
  std::printf(
      "| cells | vertices | tets | BE step (ms) | rotation-strain (ms) | ratio | modal (ms) | ratio | "
      "setup rot.-strain / modal (ms) | nnz(L factor) | max rotation (rad) |\n");
  std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const int c : cells) {
    const Row row = measure(c, repeats);
    std::printf("| %d | %d | %d | %.3f | %.3f | %.2f | %.3f | %.2f | %.1f / %.1f | %lld | %.2f |\n", c, row.vertices,
                row.elements, 1e3 * row.stepSeconds, 1e3 * row.rotationStrainSeconds,
                row.rotationStrainSeconds / row.stepSeconds, 1e3 * row.modalSeconds, row.modalSeconds / row.stepSeconds,
                1e3 * row.rotationStrainSetup, 1e3 * row.modalSetup, row.laplacianFactorNonZeros, row.maxRotation);
    std::fflush(stdout);
  }
  std::printf(
      "\nratio = warping time / step time. The step is prefactored (one back-substitution on 3n free DOFs plus\n"
      "the right-hand side); rotation-strain warping is one element pass plus a back-substitution on the n x n\n"
      "Laplacian with 3 right-hand sides; modal warping is one sparse product and a per-vertex formula.\n");
  return 0;
}
