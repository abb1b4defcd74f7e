// SPDX-License-Identifier: BSD-3-Clause
// tetMesher on the shipped example models and on surfaces of Debian's assimp-testmodels
// package (read from /usr/share/assimp/models when installed; the table says when it is
// absent). For each input: elements, wall seconds (whole pipeline: read, weld, sign,
// stuff, check), microseconds per element, dihedral-angle range, volume error and Hausdorff
// distance to the input in lattice spacings.
//
//   benchmarkTetMesher [--cells 30] [--models /usr/share/assimp/models] [--refine K] [--grade N]
//
// --refine K divides every spacing by K (the example models' shipped spacing and the
// surfaces' cells); --grade N meshes on the graded lattice (MesherOptions::gradingLevels).
//
// Volume error: closed surfaces against the divergence-theorem volume of the input; the
// implicit example models against a Monte Carlo estimate of {f < 0} (2e6 samples, relative
// standard error printed); open surfaces (meshed through the winding number) have none.
// Hausdorff: both sides for surfaces (surfaceDeviation); for the implicit models only the
// mesh-to-surface side (max |f| on the boundary, f being distance-like).
#include <CLI/CLI.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/tetMesher/exampleModels.hpp>
#include <asyncfem/tetMesher/fidelity.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "../benchmarkMachine.hpp"

namespace {

using asyncfem::bench::cpuModel;
using asyncfem::bench::loadAverage;

using namespace asyncfem;

struct Row {
  std::string name;
  std::string kind;
  int elements = 0;
  double seconds = 0.0;
  double minAngle = 0.0, maxAngle = 0.0;
  std::string volumeError;  // text: a percentage or "-"
  double hausdorffSpacings = 0.0;
  std::string note;
};

void printRow(const Row& r) {
  std::printf("| %s | %s | %d | %.2f | %.1f | %.2f | %.2f | %s | %.2f | %s |\n", r.name.c_str(), r.kind.c_str(),
              r.elements, r.seconds, 1e6 * r.seconds / std::max(1, r.elements), r.minAngle, r.maxAngle,
              r.volumeError.c_str(), r.hausdorffSpacings, r.note.c_str());
  std::fflush(stdout);
}

std::string percent(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%+.2f%%", value);
  return text;
}

struct Settings {
  int cells = 30;
  double refine = 1.0;
  int grade = 0;
};

Row exampleRow(ExampleModel model, const Settings& settings) {
  Row row;
  row.name = exampleModelName(model);
  row.kind = "implicit";
  const ImplicitModel shape = exampleModelShape(model);
  const ImplicitFunction f = implicitUnionOfParts(shape.parts, shape.blend);
  Stopwatch watch;
  watch.start();
  StuffingReport report;
  MesherOptions options;
  options.gradingLevels = settings.grade;
  const double spacing = shape.spacing / settings.refine;
  const TetMesh mesh = stuffIsosurface(f, shape.bounds, spacing, options, &report);
  row.seconds = watch.stop();
  row.elements = mesh.numElements();
  row.minAngle = report.minDihedralDegrees;
  row.maxAngle = report.maxDihedralDegrees;
  // Monte Carlo volume of {f < 0} in the bounds.
  std::mt19937_64 random(12345);
  const int samples = 2'000'000;
  const Eigen::Vector3d lo = shape.bounds.min(), size = shape.bounds.sizes();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int inside = 0;
  for (int s = 0; s < samples; ++s) {
    const Eigen::Vector3d x = lo + size.cwiseProduct(Eigen::Vector3d(unit(random), unit(random), unit(random)));
    if (f(x) < 0.0) ++inside;
  }
  const double p = static_cast<double>(inside) / samples;
  const double exact = p * size.prod();
  const double relativeError = std::sqrt((1.0 - p) / (p * samples));
  row.volumeError = percent(100.0 * (totalVolume(mesh) - exact) / exact);
  char note[96];
  std::snprintf(note, sizeof(note), "volume reference +-%.2f%%; Hausdorff mesh-to-surface only", 100.0 * relativeError);
  row.note = note;
  row.hausdorffSpacings = implicitDeviation(mesh, f) / spacing;
  return row;
}

Row surfaceRow(const std::filesystem::path& path, const Settings& settings) {
  Row row;
  row.name = path.filename().string();
  Stopwatch watch;
  watch.start();
  TriangleSurface surface = readSurface(path);
  const Eigen::AlignedBox3d bounds = surface.bounds();
  weldVertices(surface, 1e-7 * bounds.diagonal().norm());
  const SurfaceTopology topology = surfaceTopology(surface);
  const bool closed = topology.closed() && topology.degenerateTriangles == 0;
  if (topology.signedVolume < 0.0) flipOrientation(surface);
  const double spacing = bounds.sizes().maxCoeff() / (settings.cells * settings.refine);
  const SignedDistance distance(surface, closed ? SignMode::Pseudonormal : SignMode::WindingNumber);
  const Eigen::AlignedBox3d box(bounds.min().array() - spacing, bounds.max().array() + spacing);
  StuffingReport report;
  MesherOptions options;
  options.gradingLevels = settings.grade;
  const TetMesh mesh = stuffIsosurface(distance.function(), box, spacing, options, &report);
  row.seconds = watch.stop();
  row.kind = closed ? "closed" : "open (winding number)";
  row.elements = mesh.numElements();
  row.minAngle = report.minDihedralDegrees;
  row.maxAngle = report.maxDihedralDegrees;
  const double enclosed = std::abs(topology.signedVolume);
  row.volumeError = closed ? percent(100.0 * (totalVolume(mesh) - enclosed) / enclosed) : "-";
  row.hausdorffSpacings = surfaceDeviation(mesh, distance).hausdorff() / spacing;
  row.note = std::to_string(surface.numTriangles()) + " triangles";
  if (report.pinchedBoundaryEdges > 0)
    row.note += ", " + std::to_string(report.pinchedBoundaryEdges) + " pinched edges";
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tetMesher benchmark: shipped example models and assimp-testmodels surfaces"};
  Settings settings;
  std::string models = "/usr/share/assimp/models";
  app.add_option("--cells", settings.cells, "Lattice cells across the longest side of each surface's bounding box");
  app.add_option("--models", models, "Directory of Debian's assimp-testmodels");
  app.add_option("--refine", settings.refine, "Divide every spacing by this factor")->check(CLI::PositiveNumber);
  app.add_option("--grade", settings.grade, "Graded lattice levels (0: uniform)")
      ->check(CLI::Range(0, kMaxGradingLevels));
  CLI11_PARSE(app, argc, argv);
  const int cells = settings.cells;

  std::printf("machine: %s, %u hardware threads; load average before: %s\n", cpuModel().c_str(),
              std::thread::hardware_concurrency(), loadAverage().c_str());
  std::printf("command: benchmarkTetMesher --cells %d --models %s --refine %g --grade %d\n\n", cells, models.c_str(),
              settings.refine, settings.grade);
  std::printf(
      "| input | kind | elements | seconds | us/element | min angle | max angle | volume error | Hausdorff "
      "(spacings) | notes |\n|---|---|---|---|---|---|---|---|---|---|\n");
  for (ExampleModel model : {ExampleModel::Dinosaur, ExampleModel::Flower, ExampleModel::Dragon, ExampleModel::Drop})
    printRow(exampleRow(model, settings));

  // Closed surfaces first, then open ones meshed through the winding number.
  const std::vector<std::string> surfaces{"Collada/duck.dae",
                                          "3DS/fels.3ds",
                                          "Collada/sphere.dae",
                                          "FBX/huesitos.fbx",
                                          "Collada/earthCylindrical.DAE",
                                          "OBJ/box.obj",
                                          "glTF/TwoBoxes/TwoBoxes.gltf",
                                          "OBJ/WusonOBJ.obj",
                                          "OBJ/spider.obj",
                                          "STL/sphereWithHole.stl",
                                          "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf"};
  if (!surfaceReaderAvailable()) {
    std::printf("\nassimp is not compiled in (ASYNCFEM_WITH_ASSIMP=OFF): surfaces skipped\n");
  } else if (!std::filesystem::is_directory(models)) {
    std::printf(
        "\n%s is absent: install Debian's assimp-testmodels (apt-get install assimp-testmodels) for the "
        "surface rows\n",
        models.c_str());
  } else {
    for (const std::string& relative : surfaces) {
      const std::filesystem::path path = std::filesystem::path(models) / relative;
      if (!std::filesystem::exists(path)) {
        std::printf("| %s | missing from %s | | | | | | | | |\n", relative.c_str(), models.c_str());
        continue;
      }
      try {
        printRow(surfaceRow(path, settings));
      } catch (const Error& e) {
        std::printf("| %s | error | | | | | | | | %s |\n", relative.c_str(), e.what());
      }
    }
  }
  std::printf("\nload average after: %s\n", loadAverage().c_str());
  return 0;
}
