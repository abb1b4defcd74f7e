// SPDX-License-Identifier: BSD-3-Clause
// tetMesher: a closed surface (any format assimp reads) or a built-in example model to a
// quality tetrahedral mesh by isosurface stuffing, written as .veg (or .vtu).
//
//   tetMesher SURFACE --output OUT.veg [--spacing H | --cells N] [--set NAME:x0,y0,z0,x1,y1,z1]...
//             [--part-sets] [--material SET:rho,E,nu]... [--default-material rho,E,nu]
//             [--repair] [--weld-tolerance T] [--quiet]
//   tetMesher --model dinosaur|flower|dragon|drop|ball --output OUT.veg [--spacing H] [--set ...]
//   tetMesher SURFACE|--model NAME --cubes --output OUT.veg [--spacing H | --cells N] [--max-cubes N]
//
// With --cubes the solid becomes trilinear hexahedra instead: the cubes of a regular grid whose
// centres are inside (voxelize.hpp), written as Vega CUBIC elements (or VTK hexahedra).
//
// The report goes to stdout; errors print "tetMesher: <message>" on stderr and exit 1
// (2 for unusable command-line options). docs/tet-mesher.md describes everything.
#include <CLI/CLI.hpp>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/tetMesher/elementSets.hpp>
#include <asyncfem/tetMesher/exampleModels.hpp>
#include <asyncfem/tetMesher/fidelity.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <asyncfem/tetMesher/voxelize.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "commandLine.hpp"

namespace {

using asyncfem::TetMesh;
using asyncfem::ValidationError;

/// Parses "a,b,c,..." into exactly `count` finite numbers.
std::vector<double> parseNumbers(const std::string& text, std::size_t count, const std::string& what) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    while (used < item.size() && std::isspace(static_cast<unsigned char>(item[used]))) ++used;
    if (used == 0 || used != item.size() || !std::isfinite(value)) {
      throw ValidationError(what + ": \"" + item + "\" is not a number");
    }
    values.push_back(value);
  }
  if (values.size() != count) {
    throw ValidationError(what + ": expected " + std::to_string(count) + " comma-separated numbers, got " +
                          std::to_string(values.size()));
  }
  return values;
}

/// Splits "NAME:rest" at the first colon.
std::pair<std::string, std::string> splitName(const std::string& text, const std::string& what) {
  const std::size_t colon = text.find(':');
  if (colon == std::string::npos || colon == 0)
    throw ValidationError(what + ": expected NAME:values, got \"" + text + "\"");
  return {text.substr(0, colon), text.substr(colon + 1)};
}

std::string describe(const Eigen::Vector3d& x) {
  char text[96];
  std::snprintf(text, sizeof(text), "(%.6g, %.6g, %.6g)", x.x(), x.y(), x.z());
  return text;
}

void requireFiniteVertices(const asyncfem::TriangleSurface& surface, const std::string& source) {
  for (int v = 0; v < surface.numVertices(); ++v) {
    if (!surface.vertices.col(v).allFinite()) {
      throw ValidationError(source + ": vertex #" + std::to_string(v) + " has a non-finite coordinate");
    }
  }
}

bool zeroArea(const asyncfem::TriangleSurface& surface, int t) {
  const Eigen::Vector3d a = surface.vertices.col(surface.triangles(0, t));
  return (surface.vertices.col(surface.triangles(1, t)) - a)
             .cross(surface.vertices.col(surface.triangles(2, t)) - a)
             .norm() == 0.0;
}

int firstDegenerateTriangle(const asyncfem::TriangleSurface& surface) {
  for (int t = 0; t < surface.numTriangles(); ++t)
    if (zeroArea(surface, t)) return t;
  return -1;
}

/// Removes zero-area triangles (they enclose nothing and add no winding number); returns
/// how many.
int dropDegenerateTriangles(asyncfem::TriangleSurface& surface) {
  std::vector<int> keep;
  for (int t = 0; t < surface.numTriangles(); ++t)
    if (!zeroArea(surface, t)) keep.push_back(t);
  const int dropped = surface.numTriangles() - static_cast<int>(keep.size());
  asyncfem::selectTriangles(surface, keep);
  return dropped;
}

struct Options {
  std::string input;
  std::string model;
  std::string output;
  double spacing = 0.0;
  int cells = 0;
  int grade = 0;
  std::vector<std::string> boxSets;
  bool partSets = false;
  bool materialSets = false;
  bool groupSets = false;
  std::vector<std::string> materials;
  std::string defaultMaterial;
  bool repair = false;
  double maxHole = 0.2;
  double weldTolerance = -1.0;
  bool quiet = false;
  bool cubes = false;
  long long maxCubes = asyncfem::VoxelOptions{}.maxCubes;
};

void printQuality(const TetMesh& mesh, const asyncfem::StuffingReport& stuffing, double spacing) {
  const asyncfem::MeshQuality quality = asyncfem::meshQuality(mesh);
  const asyncfem::MeshCheckReport check = asyncfem::checkTetMesh(mesh);
  std::printf("lattice: spacing %.6g, %lld lattice vertices, %d vertices warped onto the surface, %d cut points\n",
              spacing, stuffing.latticeVertices, stuffing.warpedVertices, stuffing.cutPoints);
  if (stuffing.gradingLevels > 0) {
    std::printf("grading: %d levels (interior cubes up to %g), %lld leaf cubes, %d extra refinement round%s\n",
                stuffing.gradingLevels, spacing * static_cast<double>(1 << stuffing.gradingLevels),
                stuffing.latticeCells, stuffing.refinementRounds, stuffing.refinementRounds == 1 ? "" : "s");
  }
  if (stuffing.unwarpedVertices > 0) {
    std::printf(
        "pinches: %d vertices left on the lattice to keep the boundary manifold (thin parts); the angle "
        "bound does not hold next to them\n",
        stuffing.unwarpedVertices);
  }
  std::printf("mesh: %d vertices, %d tetrahedra, %d boundary triangles, %d connected component%s\n", mesh.numVertices(),
              mesh.numElements(), check.boundaryTriangles, check.components, check.components == 1 ? "" : "s");
  std::printf(
      "quality: dihedral angles min %.2f, max %.2f degrees (guaranteed 10.78 to 164.74); worst aspect ratio "
      "%.3f\n",
      quality.minDihedralDegrees, quality.maxDihedralDegrees, quality.worstAspectRatio);
  if (check.pinchedBoundaryEdges > 0) {
    std::printf(
        "pinches: %d boundary edges where two sheets of the surface touch (parts or gaps thinner than the "
        "spacing); valid, but a smaller --spacing resolves them\n",
        check.pinchedBoundaryEdges);
  }
  std::printf("checks: no inverted or degenerate element, every vertex used, boundary closed and outward\n");
}

void printSets(const TetMesh& mesh) {
  for (const auto& [name, members] : mesh.elementSets()) {
    std::printf("set %s: %zu elements, %zu vertices\n", name.c_str(), members.size(), mesh.vertexSet(name).size());
  }
  for (const asyncfem::Material& m : mesh.materials()) {
    std::printf("material %s: density %g, Young's modulus %g, Poisson ratio %g\n", m.name.c_str(), m.density,
                m.youngsModulus, m.poissonRatio);
  }
}

/// A built-in example model at the given spacing (its own when <= 0).
TetMesh meshModel(const Options& options, double& spacing, asyncfem::StuffingReport& stuffing) {
  const asyncfem::ExampleModel model = asyncfem::exampleModelFromName(options.model);
  if (options.cells > 0) throw ValidationError("--cells applies to surfaces; give --spacing for a model");
  if (spacing <= 0.0) spacing = asyncfem::exampleModelShape(model).spacing;
  TetMesh mesh = asyncfem::makeExampleModel(model, spacing, &stuffing, options.grade);
  if (!options.quiet) {
    const asyncfem::ImplicitModel shape = asyncfem::exampleModelShape(model);
    Eigen::Vector3d at = Eigen::Vector3d::Zero();
    const double deviation =
        asyncfem::implicitDeviation(mesh, asyncfem::implicitUnionOfParts(shape.parts, shape.blend), &at);
    std::printf("model: %s\n", options.model.c_str());
    std::printf("fidelity: mesh boundary to surface at most %.4g (%.2f spacings, |f| sampled) at %s\n", deviation,
                deviation / spacing, describe(at).c_str());
  }
  return mesh;
}

/// The input surface, read, welded, checked and oriented outward, with how to sign it.
struct PreparedSurface {
  asyncfem::TriangleSurface surface;
  asyncfem::SignMode mode = asyncfem::SignMode::Pseudonormal;
  Eigen::AlignedBox3d inputBounds;  ///< before welding
  double enclosed = 0.0;            ///< |divergence-theorem volume|
};

/// Zero-area triangles have no normal: an error for the pseudonormal sign, dropped (they
/// add no winding number) for the winding number.
void handleDegenerateTriangles(PreparedSurface& prepared, int degenerate, const Options& options) {
  const int first = firstDegenerateTriangle(prepared.surface);
  const Eigen::Vector3d at = prepared.surface.vertices.col(prepared.surface.triangles(0, first));
  if (prepared.mode == asyncfem::SignMode::Pseudonormal) {
    throw ValidationError(
        options.input + ": " + std::to_string(degenerate) + " triangles have zero area, e.g. triangle #" +
        std::to_string(asyncfem::inputTriangleIndex(prepared.surface, first)) + " at " + describe(at) +
        "; their normals are undefined, so inside and outside cannot be told there (remove "
        "them, or mesh with --repair, which ignores them)");
  }
  const int dropped = dropDegenerateTriangles(prepared.surface);
  if (!options.quiet) {
    std::printf("repair: %d zero-area triangles ignored (e.g. #%d at %s)\n", dropped,
                asyncfem::inputTriangleIndex(prepared.surface, first), describe(at).c_str());
  }
}

PreparedSurface prepareSurface(const Options& options) {
  PreparedSurface prepared;
  prepared.surface = asyncfem::readSurface(options.input);
  asyncfem::TriangleSurface& surface = prepared.surface;
  requireFiniteVertices(surface, options.input);
  const int inputVertices = surface.numVertices();
  prepared.inputBounds = surface.bounds();
  const double diagonal = prepared.inputBounds.diagonal().norm();
  const double tolerance = options.weldTolerance >= 0.0 ? options.weldTolerance : 1e-7 * diagonal;
  const int welded = asyncfem::weldVertices(surface, tolerance);
  const asyncfem::SurfaceTopology topology = asyncfem::surfaceTopology(surface);
  if (!options.quiet) {
    std::printf("surface: %s: %d triangles, %d vertices (%d welded away from %d at tolerance %.3g), %zu part%s\n",
                options.input.c_str(), surface.numTriangles(), surface.numVertices(), welded, inputVertices, tolerance,
                surface.partNames.size(), surface.partNames.size() == 1 ? "" : "s");
  }
  if (options.repair) prepared.mode = asyncfem::SignMode::WindingNumber;
  if (!topology.closed()) {
    if (!options.repair) asyncfem::requireClosedSurface(surface, options.input);
    if (!options.quiet) {
      std::printf(
          "repair: the surface is not closed (%d open, %d non-manifold, %d inconsistently oriented edges, "
          "e.g. %s); inside/outside from the generalized winding number\n",
          topology.boundaryEdges, topology.nonManifoldEdges, topology.misorientedEdges, topology.example.c_str());
    }
  }
  if (topology.degenerateTriangles > 0) handleDegenerateTriangles(prepared, topology.degenerateTriangles, options);
  if (topology.signedVolume < 0.0) {
    asyncfem::flipOrientation(surface);
    if (!options.quiet) std::printf("surface: normals pointed inward; triangles reversed\n");
  }
  prepared.enclosed = std::abs(topology.signedVolume);
  return prepared;
}

/// Refuses meshes that span too much of an open input or overlap themselves; prints volume
/// and Hausdorff distance.
void checkAndReportSurfaceMesh(const TetMesh& mesh, const asyncfem::SignedDistance& distance,
                               const PreparedSurface& prepared, double spacing, const Options& options) {
  const asyncfem::SurfaceDeviation deviation = asyncfem::surfaceDeviation(mesh, distance);
  if (prepared.mode == asyncfem::SignMode::WindingNumber) {
    const double invented = asyncfem::requireRepairableHoles(mesh, distance, spacing, options.maxHole, options.input);
    if (!options.quiet) {
      std::printf("repair: %.2f%% of the boundary spans openings of the input (more than a spacing from it)\n",
                  100.0 * invented);
    }
  } else {
    asyncfem::requireNoSelfOverlap(mesh, distance, options.input);
  }
  if (options.quiet) return;
  const double volume = asyncfem::totalVolume(mesh);
  const double enclosed = prepared.enclosed;
  if (prepared.mode == asyncfem::SignMode::Pseudonormal && enclosed > 0.0) {
    std::printf("volume: mesh %.6g, surface %.6g (%+.2f%%)\n", volume, enclosed,
                100.0 * (volume - enclosed) / enclosed);
  } else {
    std::printf(
        "volume: mesh %.6g (the open surface encloses no definite volume; its divergence-theorem "
        "value is %.6g)\n",
        volume, enclosed);
  }
  std::printf(
      "fidelity: sampled Hausdorff distance %.4g (%.2f spacings; at the triangles' vertices, edge midpoints and "
      "centroids, a lower bound of the exact distance): mesh to surface %.4g at %s, surface to mesh %.4g at %s "
      "(triangle #%d)\n",
      deviation.hausdorff(), deviation.hausdorff() / spacing, deviation.meshToSurface,
      describe(deviation.meshToSurfaceAt).c_str(), deviation.surfaceToMesh, describe(deviation.surfaceToMeshAt).c_str(),
      asyncfem::inputTriangleIndex(distance.surface(), deviation.surfaceToMeshTriangle));
}

/// --part-sets, --material-sets, --group-sets.
void addRequestedLabelSets(TetMesh& mesh, const asyncfem::SignedDistance& distance, const Options& options) {
  if (options.partSets) asyncfem::addSurfaceLabelSets(mesh, distance, asyncfem::SurfaceLabel::Part);
  if (options.materialSets) asyncfem::addSurfaceLabelSets(mesh, distance, asyncfem::SurfaceLabel::Material);
  if (options.groupSets) asyncfem::addSurfaceLabelSets(mesh, distance, asyncfem::SurfaceLabel::Group);
}

/// A surface file at the given spacing (from --cells, default 30, when <= 0).
TetMesh meshSurface(const Options& options, const asyncfem::MesherOptions& mesherOptions, double& spacing,
                    asyncfem::StuffingReport& stuffing) {
  PreparedSurface prepared = prepareSurface(options);
  const Eigen::AlignedBox3d& inputBounds = prepared.inputBounds;
  if (spacing <= 0.0) spacing = inputBounds.sizes().maxCoeff() / (options.cells > 0 ? options.cells : 30);
  const asyncfem::SignedDistance distance(std::move(prepared.surface), prepared.mode);
  const Eigen::AlignedBox3d bounds(inputBounds.min().array() - spacing, inputBounds.max().array() + spacing);
  TetMesh mesh = asyncfem::stuffIsosurface(distance.function(), bounds, spacing, mesherOptions, &stuffing);
  checkAndReportSurfaceMesh(mesh, distance, prepared, spacing, options);
  addRequestedLabelSets(mesh, distance, options);
  return mesh;
}

void printCubes(const asyncfem::VoxelReport& report, double spacing) {
  std::printf("cubes: spacing %.6g, grid %d x %d x %d (%lld cells), %d cubes, %d vertices, %.3f s\n", spacing,
              report.gridCells.x(), report.gridCells.y(), report.gridCells.z(), report.gridCellCount, report.cubes,
              report.vertices, report.seconds);
}

/// --cubes: the surface or the model as cubes whose centres are inside, with its volume error.
TetMesh meshCubes(const Options& options, const asyncfem::MesherOptions& mesherOptions, double& spacing) {
  if (options.grade > 0) throw ValidationError("--grade applies to tetrahedra; --cubes makes a uniform grid");
  asyncfem::VoxelOptions voxelOptions;
  voxelOptions.material = mesherOptions.material;
  voxelOptions.maxCubes = options.maxCubes;
  asyncfem::VoxelReport report;
  if (!options.model.empty()) {
    const asyncfem::ExampleModel model = asyncfem::exampleModelFromName(options.model);
    if (options.cells > 0) throw ValidationError("--cells applies to surfaces; give --spacing for a model");
    if (spacing <= 0.0) spacing = asyncfem::exampleModelShape(model).spacing;
    TetMesh mesh = asyncfem::makeExampleModelCubes(model, spacing, &report);
    if (!options.quiet) {
      printCubes(report, spacing);
      std::printf("volume: cubes %.6g (an implicit model has no reference volume to compare with)\n",
                  report.cubeVolume);
    }
    return mesh;
  }
  PreparedSurface prepared = prepareSurface(options);
  if (spacing <= 0.0) spacing = prepared.inputBounds.sizes().maxCoeff() / (options.cells > 0 ? options.cells : 30);
  const asyncfem::SignedDistance distance(std::move(prepared.surface), prepared.mode);
  TetMesh mesh = asyncfem::voxelize(distance.function(), prepared.inputBounds, spacing, voxelOptions, &report);
  if (prepared.mode == asyncfem::SignMode::Pseudonormal) {
    asyncfem::requireNoSelfOverlap(mesh, distance, options.input);
  } else {
    // Cube faces lie within sqrt(3) / 2 spacings of the solid's surface; farther ones span holes.
    asyncfem::requireRepairableHoles(mesh, distance, spacing, options.maxHole, options.input);
  }
  addRequestedLabelSets(mesh, distance, options);
  if (options.quiet) return mesh;
  printCubes(report, spacing);
  if (prepared.mode == asyncfem::SignMode::Pseudonormal && prepared.enclosed > 0.0) {
    std::printf("volume: cubes %.6g, surface %.6g, error %+.2f%%\n", report.cubeVolume, prepared.enclosed,
                100.0 * asyncfem::relativeVolumeError(report.cubeVolume, prepared.enclosed));
  } else {
    std::printf(
        "volume: cubes %.6g (the open surface encloses no definite volume; its divergence-theorem value is "
        "%.6g)\n",
        report.cubeVolume, prepared.enclosed);
  }
  return mesh;
}

/// --set boxes and --material assignments, in the order given.
void addRequestedSets(TetMesh& mesh, const Options& options) {
  for (const std::string& text : options.boxSets) {
    const auto [name, numbers] = splitName(text, "--set");
    const std::vector<double> v = parseNumbers(numbers, 6, "--set " + name);
    const Eigen::AlignedBox3d box(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
    if (box.isEmpty()) throw ValidationError("--set " + name + ": expected min <= max");
    if (asyncfem::addBoxSet(mesh, name, box) == 0) {
      throw ValidationError("--set " + name + ": no element centroid lies in the box");
    }
  }
  for (const std::string& text : options.materials) {
    const auto [name, numbers] = splitName(text, "--material");
    const std::vector<double> v = parseNumbers(numbers, 3, "--material " + name);
    asyncfem::assignSetMaterial(mesh, name, asyncfem::Material{name, v[0], v[1], v[2]});
  }
}

int run(const Options& options) {
  if (options.input.empty() == options.model.empty()) {
    throw ValidationError("give either a surface file or --model NAME");
  }
  if (options.spacing > 0.0 && options.cells > 0) throw ValidationError("give either --spacing or --cells, not both");
  asyncfem::MesherOptions mesherOptions;
  mesherOptions.gradingLevels = options.grade;
  if (!options.defaultMaterial.empty()) {
    const std::vector<double> v = parseNumbers(options.defaultMaterial, 3, "--default-material");
    mesherOptions.material = asyncfem::Material{"default", v[0], v[1], v[2]};
  }
  asyncfem::StuffingReport stuffing;
  double spacing = options.spacing;
  TetMesh mesh = options.cubes           ? meshCubes(options, mesherOptions, spacing)
                 : options.model.empty() ? meshSurface(options, mesherOptions, spacing, stuffing)
                                         : meshModel(options, spacing, stuffing);
  addRequestedSets(mesh, options);
  if (options.cubes) {
    if (!options.quiet) printSets(mesh);
  } else if (!options.quiet) {
    printQuality(mesh, stuffing, spacing);
    printSets(mesh);
  }
  const std::filesystem::path output(options.output);
  if (output.has_parent_path()) std::filesystem::create_directories(output.parent_path());
  if (output.extension() == ".vtu") {
    asyncfem::writeVtu(output, mesh);
  } else {
    asyncfem::writeVeg(output, mesh);  // the extension was checked in main
  }
  if (!options.quiet) std::printf("wrote %s\n", options.output.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{
      "Tetrahedral meshes by isosurface stuffing (or cube meshes with --cubes) from closed surfaces or built-in "
      "example models"};
  Options options;
  app.add_option("surface", options.input,
                 "Closed triangle surface (any format assimp reads: OBJ, STL, PLY, OFF, ...)");
  app.add_option("--model", options.model, "Built-in example model: dinosaur, flower, dragon, drop, ball");
  app.add_option("-o,--output", options.output, "Output mesh (.veg, or .vtu for ParaView)")->required();
  app.add_option("--spacing", options.spacing,
                 "BCC lattice spacing, or with --cubes the cube edge (length units of the input)")
      ->check(asyncfem::cli::positive());
  app.add_option("--cells", options.cells, "Lattice cells across the longest side of the bounding box (default 30)")
      ->check(asyncfem::cli::inRange(1, 2000));
  app.add_option("--grade", options.grade,
                 "Graded lattice: the spacing near the surface, cubes up to 2^LEVELS spacings inside (default 0: "
                 "uniform)")
      ->check(asyncfem::cli::inRange(0, asyncfem::kMaxGradingLevels));
  app.add_option("--set", options.boxSets,
                 "Element and vertex set of the elements whose centroid lies in a box: "
                 "NAME:xmin,ymin,zmin,xmax,ymax,zmax (repeatable)");
  // Surface label sets (addSurfaceLabelSets): by assimp part, file material or named group.
  const std::array<std::tuple<const char*, bool*, const char*>, 3> labelSets{{
      {"--part-sets", &options.partSets, "named surface part (assimp mesh/node name)"},
      {"--material-sets", &options.materialSets, "material of the surface file"},
      {"--group-sets", &options.groupSets, "named group of the surface file (OBJ g/o, glTF/FBX nodes)"},
  }};
  for (const auto& [flag, target, what] : labelSets) {
    app.add_flag(flag, *target,
                 std::string("One set per ") + what +
                     ", named after it: the elements inside its triangles (innermost first), else nearest to them");
  }
  app.add_option("--material", options.materials,
                 "Material of a set: SET:density,youngsModulus,poissonRatio (repeatable)");
  app.add_option("--default-material", options.defaultMaterial,
                 "Material of all other elements: density,E,nu "
                 "(default 1000,1e6,0.45)");
  app.add_flag("--repair", options.repair,
               "Mesh a surface with holes or non-manifold edges using the generalized winding number");
  app.add_option("--max-hole", options.maxHole,
                 "With --repair: the largest share of the mesh boundary that may span openings of the input "
                 "(farther than a spacing from it; default 0.2); more is an error naming the place")
      ->check(asyncfem::cli::positive());
  app.add_option("--weld-tolerance", options.weldTolerance,
                 "Merge surface vertices closer than this (default 1e-7 x bounding-box diagonal)");
  app.add_flag("--cubes", options.cubes,
               "Cubes instead of tetrahedra: the cells of a grid at --spacing whose centres are inside, written "
               "as hexahedra (Vega CUBIC)");
  app.add_option("--max-cubes", options.maxCubes, "With --cubes: the most cubes allowed (default 2000000)")
      ->check(asyncfem::cli::inRange(1, 100000000));
  app.add_flag("-q,--quiet", options.quiet, "Print nothing but errors");
  if (const std::optional<int> status = asyncfem::cli::parse(app, argc, argv, "tetMesher")) return *status;
  return asyncfem::cli::run("tetMesher", [&] {
    // Before any meshing, so a typo does not cost the whole run.
    const std::string extension = std::filesystem::path(options.output).extension().string();
    if (extension != ".veg" && extension != ".vtu") {
      throw asyncfem::cli::UsageError("--output: cannot write '" + options.output + "': unknown extension '" +
                                      extension + "' (supported: .veg, .vtu)");
    }
    return run(options);
  });
}
