// SPDX-License-Identifier: BSD-3-Clause
// meshInfo: reads (or generates) a tetrahedral mesh and prints what it contains.
//
//   meshInfo FILE [--json] [--write OUT.veg|OUT.vtu]
//   meshInfo --generate beam|box|antenna|snail [--cells N] [--json] [--write OUT]
//
// Text goes to stdout, reader warnings to stderr; errors print "meshInfo: <message>"
// on stderr and exit with status 1.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "commandLine.hpp"

namespace {

using asyncfem::TetMesh;

struct QualitySummary {
  double minDihedralDegrees = 0.0;   ///< smallest min dihedral angle over elements
  double meanDihedralDegrees = 0.0;  ///< mean over elements of the min dihedral angle
  double maxDihedralDegrees = 0.0;   ///< largest min dihedral angle over elements
  double worstAspectRatio = 0.0;
};

QualitySummary summarizeQuality(const TetMesh& mesh) {
  QualitySummary s;
  if (mesh.numElements() == 0) return s;
  const double toDegrees = 180.0 / std::numbers::pi;
  s.minDihedralDegrees = std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (const asyncfem::ElementQuality& q : asyncfem::elementQualities(mesh)) {
    const double angle = q.minDihedralAngle * toDegrees;
    s.minDihedralDegrees = std::min(s.minDihedralDegrees, angle);
    s.maxDihedralDegrees = std::max(s.maxDihedralDegrees, angle);
    sum += angle;
    s.worstAspectRatio = std::max(s.worstAspectRatio, q.aspectRatio);
  }
  s.meanDihedralDegrees = sum / mesh.numElements();
  return s;
}

nlohmann::json describe(const TetMesh& mesh, const std::string& source, const asyncfem::MeshReadReport& report) {
  nlohmann::json j;
  j["file"] = source;
  j["format"] = report.format;
  j["vertices"] = mesh.numVertices();
  j["elements"] = mesh.numElements();
  std::vector<int> perMaterial(mesh.materials().size(), 0);
  for (int m : mesh.elementMaterials()) ++perMaterial[static_cast<std::size_t>(m)];
  j["materials"] = nlohmann::json::array();
  for (std::size_t m = 0; m < mesh.materials().size(); ++m) {
    const asyncfem::Material& mat = mesh.materials()[m];
    j["materials"].push_back({{"name", mat.name},
                              {"density", mat.density},
                              {"youngsModulus", mat.youngsModulus},
                              {"poissonRatio", mat.poissonRatio},
                              {"elements", perMaterial[m]}});
  }
  j["elementSets"] = nlohmann::json::object();
  for (const auto& [name, members] : mesh.elementSets()) j["elementSets"][name] = members.size();
  j["vertexSets"] = nlohmann::json::object();
  for (const auto& [name, members] : mesh.vertexSets()) j["vertexSets"][name] = members.size();
  j["volume"] = asyncfem::totalVolume(mesh);
  j["mass"] = asyncfem::totalMass(mesh);
  j["boundaryTriangles"] = asyncfem::boundaryTriangles(mesh).size();
  const asyncfem::BoundingBox box = asyncfem::boundingBox(mesh);
  j["boundingBox"] = {{"min", {box.min.x(), box.min.y(), box.min.z()}},
                      {"max", {box.max.x(), box.max.y(), box.max.z()}}};
  const QualitySummary q = summarizeQuality(mesh);
  j["quality"] = {{"minDihedralAngleDegrees",
                   {{"min", q.minDihedralDegrees}, {"mean", q.meanDihedralDegrees}, {"max", q.maxDihedralDegrees}}},
                  {"worstAspectRatio", q.worstAspectRatio}};
  j["reorientedElements"] = report.reorientedElements;
  j["unusedVertices"] = report.unusedVertices;
  j["ignoredElements"] = report.ignoredElements;
  j["warnings"] = report.warnings;
  return j;
}

void printText(const nlohmann::json& j) {
  std::cout << "file: " << j["file"].get<std::string>() << '\n'
            << "format: " << j["format"].get<std::string>() << '\n'
            << "vertices: " << j["vertices"] << '\n'
            << "elements: " << j["elements"] << '\n'
            << "materials:\n";
  for (const auto& m : j["materials"]) {
    std::cout << "  " << m["name"].get<std::string>() << ": density " << m["density"] << ", E " << m["youngsModulus"]
              << ", nu " << m["poissonRatio"] << ", elements " << m["elements"] << '\n';
  }
  std::cout << "element sets:" << (j["elementSets"].empty() ? " none" : "") << '\n';
  for (const auto& [name, size] : j["elementSets"].items()) std::cout << "  " << name << ": " << size << '\n';
  std::cout << "vertex sets:" << (j["vertexSets"].empty() ? " none" : "") << '\n';
  for (const auto& [name, size] : j["vertexSets"].items()) std::cout << "  " << name << ": " << size << '\n';
  const auto& box = j["boundingBox"];
  std::cout << "volume: " << j["volume"] << '\n'
            << "mass: " << j["mass"] << '\n'
            << "boundary triangles: " << j["boundaryTriangles"] << '\n'
            << "bounding box: [" << box["min"][0] << ", " << box["min"][1] << ", " << box["min"][2] << "] - ["
            << box["max"][0] << ", " << box["max"][1] << ", " << box["max"][2] << "]\n";
  const auto& dihedral = j["quality"]["minDihedralAngleDegrees"];
  std::cout << "min dihedral angle (degrees): min " << dihedral["min"] << ", mean " << dihedral["mean"] << ", max "
            << dihedral["max"] << '\n'
            << "worst aspect ratio: " << j["quality"]["worstAspectRatio"] << '\n'
            << "reoriented elements: " << j["reorientedElements"] << '\n';
}

int run(int argc, char** argv) {
  CLI::App app{
      "Print the contents of a tetrahedral mesh (.veg, TetGen .node/.ele, Gmsh .msh), "
      "or generate a beam, box, antenna or snail mesh."};
  std::string input;
  std::string output;
  std::string generate;
  int cells = 0;
  bool json = false;
  app.add_option("file", input, "mesh file to read (.veg, .node, .ele, .msh)");
  app.add_option("--generate", generate,
                 "generate instead of reading: beam (makeBeamMesh), box (makeBoxMesh), antenna (makeAntennaMesh) "
                 "or snail (makeSnailMesh)")
      ->check(CLI::IsMember({"beam", "box", "antenna", "snail"}));
  app.add_option("--cells", cells,
                 "with --generate: beam cells along the length (default 20), box cells per axis (default 4), "
                 "antenna rod cells (default 8) or snail tentacle cells (default 6)")
      ->check(asyncfem::cli::inRange(1, 1000));
  std::vector<int> blockCells;
  app.add_option("--block-cells", blockCells,
                 "with --generate antenna: the block's cells along x, y (up) and z "
                 "(default 10 4 10)")
      ->expected(3)
      ->check(asyncfem::cli::inRange(1, 1000));
  app.add_flag("--json", json, "print a JSON object instead of text");
  app.add_option("--write", output, "also write the mesh to OUT.veg or OUT.vtu");
  if (const std::optional<int> status = asyncfem::cli::parse(app, argc, argv, "meshInfo")) return *status;
  // Checked before any work, so a typo does not cost a mesh generation or read.
  const std::string extension = std::filesystem::path(output).extension().string();
  if (!output.empty() && extension != ".veg" && extension != ".vtu") {
    throw asyncfem::cli::UsageError("--write: cannot write '" + output + "': unknown extension '" + extension +
                                    "' (supported: .veg, .vtu)");
  }
  if (input.empty() == generate.empty())
    throw asyncfem::Error("give either a mesh file or --generate beam|box|antenna|snail (see --help)");
  if (cells != 0 && generate.empty()) throw asyncfem::Error("--cells only applies to --generate");
  if (!blockCells.empty() && generate != "antenna")
    throw asyncfem::Error("--block-cells only applies to --generate antenna");

  TetMesh mesh;
  asyncfem::MeshReadReport report;
  std::string source = input;
  if (!generate.empty()) report.format = "generated";
  if (generate == "beam") {
    asyncfem::BeamSpec spec;
    if (cells > 0) spec.cellsAlongLength = cells;
    mesh = asyncfem::makeBeamMesh(spec);
    source = "generated beam, " + std::to_string(spec.cellsAlongLength) + " cells along the length";
  } else if (generate == "box") {
    asyncfem::BoxMeshSpec spec;
    if (cells > 0) spec.cells = Eigen::Vector3i::Constant(cells);
    mesh = asyncfem::makeBoxMesh(spec);
    source = "generated box, " + std::to_string(spec.cells.x()) + " cells per axis";
  } else if (generate == "antenna") {
    asyncfem::AntennaSpec spec;
    if (cells > 0) spec.rodCells = cells;
    if (!blockCells.empty()) spec.blockCells = Eigen::Vector3i(blockCells[0], blockCells[1], blockCells[2]);
    mesh = asyncfem::makeAntennaMesh(spec);
    source = "generated antenna on a block, rod of " + std::to_string(spec.rodCells) + " cells";
  } else if (generate == "snail") {
    asyncfem::SnailSpec spec;
    if (cells > 0) spec.tentacleCells = cells;
    mesh = asyncfem::makeSnailMesh(spec);
    source = "generated snail, tentacles of " + std::to_string(spec.tentacleCells) + " cells";
  } else {
    mesh = asyncfem::readMesh(input, {}, &report);
  }
  for (const std::string& warning : report.warnings) std::cerr << "meshInfo: warning: " << warning << '\n';

  const nlohmann::json description = describe(mesh, source, report);
  if (json) {
    std::cout << description.dump(2) << '\n';
  } else {
    printText(description);
  }
  if (!output.empty()) {
    const std::string extension = std::filesystem::path(output).extension().string();
    if (extension == ".veg") {
      asyncfem::writeVeg(output, mesh);
    } else {
      asyncfem::writeVtu(output, mesh);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  return asyncfem::cli::run("meshInfo", [&] { return run(argc, argv); });
}
