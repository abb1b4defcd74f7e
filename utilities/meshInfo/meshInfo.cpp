// SPDX-License-Identifier: BSD-3-Clause
// meshInfo: reads (or generates) a tetrahedral or hexahedral mesh and prints what it contains.
//
//   meshInfo FILE [--json] [--write OUT.veg|OUT.vtu] [--rename-set OLD=NEW]... [--angle-threshold DEG]
//            [--default-material rho,E,nu] [--hex-to-tets]
//   meshInfo --generate beam|box|antenna|snail [--cells N] [--json] [--write OUT]
//
// Text goes to stdout, reader warnings to stderr; errors print "meshInfo: <message>"
// on stderr and exit with status 1.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/hexToTets.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "commandLine.hpp"

namespace {

using asyncfem::TetMesh;

nlohmann::json describe(const TetMesh& mesh, const std::string& source, const asyncfem::MeshReadReport& report,
                        double angleThreshold) {
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
  if (mesh.isHexahedral()) {
    j["elementKind"] = "hexahedra";
    const asyncfem::HexahedronQualitySummary q = asyncfem::summarizeHexahedronQuality(mesh);
    std::vector<int> inverted;  // numbered from 1, as .veg files number elements
    for (int e : q.invertedElements) inverted.push_back(e + 1);
    j["quality"] = {{"scaledJacobian", {{"min", q.minScaledJacobian}, {"meanElementMin", q.meanMinScaledJacobian}}},
                    {"worstEdgeRatio", q.worstEdgeRatio},
                    {"invertedElements", inverted}};
  } else {
    const asyncfem::QualitySummary q = asyncfem::summarizeQuality(mesh, angleThreshold);
    j["quality"] = {
        {"dihedralAngleDegrees", {{"min", q.minDihedralDegrees}, {"max", q.maxDihedralDegrees}}},
        {"meanElementMinDihedralAngleDegrees", q.meanMinDihedralDegrees},
        {"elementsBelowAngle", {{"thresholdDegrees", q.thresholdDegrees}, {"count", q.elementsBelowThreshold}}},
        {"worstAspectRatio", q.worstAspectRatio}};
  }
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
            << "elements: " << j["elements"] << '\n';
  if (j.contains("elementKind")) std::cout << "element kind: " << j["elementKind"].get<std::string>() << '\n';
  std::cout << "materials:\n";
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
  const auto& quality = j["quality"];
  if (j.contains("elementKind")) {
    std::cout << "scaled Jacobian at the corners: min " << quality["scaledJacobian"]["min"]
              << " (mean of each element's smallest " << quality["scaledJacobian"]["meanElementMin"] << ")\n"
              << "worst edge ratio: " << quality["worstEdgeRatio"] << '\n'
              << "inverted elements: " << quality["invertedElements"].size();
    const auto& inverted = quality["invertedElements"];
    constexpr std::size_t kNamed = 20;
    for (std::size_t i = 0; i < std::min(inverted.size(), kNamed); ++i)
      std::cout << (i == 0 ? " (" : ", ") << inverted[i];
    if (inverted.size() > kNamed) std::cout << ", and " << inverted.size() - kNamed << " more";
    std::cout << (inverted.empty() ? "" : ")") << '\n' << "reoriented elements: " << j["reorientedElements"] << '\n';
    return;
  }
  const auto& below = quality["elementsBelowAngle"];
  std::cout << "dihedral angles (degrees): min " << quality["dihedralAngleDegrees"]["min"] << ", max "
            << quality["dihedralAngleDegrees"]["max"] << " (mean of each element's smallest "
            << quality["meanElementMinDihedralAngleDegrees"] << ")\n"
            << "elements with a dihedral angle below " << below["thresholdDegrees"] << " degrees: " << below["count"]
            << '\n'
            << "worst aspect ratio: " << quality["worstAspectRatio"] << '\n'
            << "reoriented elements: " << j["reorientedElements"] << '\n';
}

/// The command line.
struct Options {
  std::string input;
  std::string output;
  std::string generate;
  int cells = 0;
  std::vector<int> blockCells;
  int whipCells = 0;
  bool json = false;
  std::vector<std::string> renames;     ///< OLD=NEW
  double angleThreshold = 10.0;         ///< degrees
  std::vector<double> defaultMaterial;  ///< rho, E, nu
  bool hexToTets = false;
};

void addOptions(CLI::App& app, Options& options) {
  app.add_option("file", options.input, "mesh file to read (.veg, .node, .ele, .msh)");
  app.add_option("--generate", options.generate,
                 "generate instead of reading: beam (makeBeamMesh), box (makeBoxMesh), antenna (makeAntennaMesh) "
                 "or snail (makeSnailMesh)")
      ->check(CLI::IsMember({"beam", "box", "antenna", "snail"}));
  app.add_option("--cells", options.cells,
                 "with --generate: beam cells along the length (default 20), box cells per axis (default 4), "
                 "antenna rod cells (default 8) or snail tentacle cells (default 6)")
      ->check(asyncfem::cli::inRange(1, 1000));
  app.add_option("--block-cells", options.blockCells,
                 "with --generate antenna: the block's cells along x, y (up) and z "
                 "(default 10 4 10)")
      ->expected(3)
      ->check(asyncfem::cli::inRange(1, 1000));
  app.add_option("--whip-cells", options.whipCells,
                 "with --generate antenna: the rod's top cells made a lighter \"whip\" (default 0: none), for "
                 "nested regions")
      ->check(asyncfem::cli::inRange(0, 1000));
  app.add_flag("--json", options.json, "print a JSON object instead of text");
  app.add_option("--write", options.output, "also write the mesh to OUT.veg or OUT.vtu");
  app.add_option("--rename-set", options.renames,
                 "rename a set before writing, OLD=NEW (repeatable); .veg names cannot hold spaces, commas or '#'");
  app.add_option("--angle-threshold", options.angleThreshold,
                 "count the elements with a dihedral angle below this many degrees")
      ->check(asyncfem::cli::inRange(0.0, 180.0))
      ->capture_default_str();
  app.add_option("--default-material", options.defaultMaterial,
                 "material rho,E,nu of the elements the file gives none (TetGen, Gmsh; .veg elements outside every "
                 "*REGION), instead of the default density 1000, E 1e6, nu 0.45")
      ->delimiter(',')
      ->expected(3);
  app.add_flag("--hex-to-tets", options.hexToTets,
               "split every hexahedron into 6 tetrahedra (conforming across faces) before printing and writing, so "
               "that any model runs on a cube mesh");
}

/// The two names of a --rename-set OLD=NEW.
std::pair<std::string, std::string> splitRename(const std::string& rename) {
  const std::size_t equals = rename.find('=');
  if (equals == std::string::npos || equals == 0 || equals + 1 == rename.size()) {
    throw asyncfem::cli::UsageError("--rename-set '" + rename + "': expected OLD=NEW");
  }
  return {rename.substr(0, equals), rename.substr(equals + 1)};
}

/// Checked before any work, so a typo does not cost a mesh generation or read.
void checkOptions(const Options& options) {
  const std::string extension = std::filesystem::path(options.output).extension().string();
  if (!options.output.empty() && extension != ".veg" && extension != ".vtu") {
    throw asyncfem::cli::UsageError("--write: cannot write '" + options.output + "': unknown extension '" + extension +
                                    "' (supported: .veg, .vtu)");
  }
  if (options.input.empty() == options.generate.empty())
    throw asyncfem::Error("give either a mesh file or --generate beam|box|antenna|snail (see --help)");
  if (options.cells != 0 && options.generate.empty()) throw asyncfem::Error("--cells only applies to --generate");
  if (!options.blockCells.empty() && options.generate != "antenna")
    throw asyncfem::Error("--block-cells only applies to --generate antenna");
  if (options.whipCells != 0 && options.generate != "antenna")
    throw asyncfem::Error("--whip-cells only applies to --generate antenna");
  for (const std::string& rename : options.renames) (void)splitRename(rename);
  if (!options.defaultMaterial.empty() && !options.generate.empty())
    throw asyncfem::Error("--default-material only applies to a mesh file");
}

/// The mesh --generate names, with its description in source.
TetMesh generateMesh(const Options& options, std::string& source) {
  const int cells = options.cells;
  if (options.generate == "beam") {
    asyncfem::BeamSpec spec;
    if (cells > 0) spec.cellsAlongLength = cells;
    source = "generated beam, " + std::to_string(spec.cellsAlongLength) + " cells along the length";
    return asyncfem::makeBeamMesh(spec);
  }
  if (options.generate == "box") {
    asyncfem::BoxMeshSpec spec;
    if (cells > 0) spec.cells = Eigen::Vector3i::Constant(cells);
    source = "generated box, " + std::to_string(spec.cells.x()) + " cells per axis";
    return asyncfem::makeBoxMesh(spec);
  }
  if (options.generate == "antenna") {
    asyncfem::AntennaSpec spec;
    if (cells > 0) spec.rodCells = cells;
    const std::vector<int>& block = options.blockCells;
    if (!block.empty()) spec.blockCells = Eigen::Vector3i(block[0], block[1], block[2]);
    spec.whipCells = options.whipCells;
    source = "generated antenna on a block, rod of " + std::to_string(spec.rodCells) + " cells";
    if (spec.whipCells > 0) source += ", the top " + std::to_string(spec.whipCells) + " a lighter whip";
    return asyncfem::makeAntennaMesh(spec);
  }
  asyncfem::SnailSpec spec;
  if (cells > 0) spec.tentacleCells = cells;
  source = "generated snail, tentacles of " + std::to_string(spec.tentacleCells) + " cells";
  return asyncfem::makeSnailMesh(spec);
}

int run(int argc, char** argv) {
  CLI::App app{
      "Print the contents of a tetrahedral or hexahedral mesh (.veg, TetGen .node/.ele, Gmsh .msh), "
      "or generate a beam, box, antenna or snail mesh."};
  Options options;
  addOptions(app, options);
  if (const std::optional<int> status = asyncfem::cli::parse(app, argc, argv, "meshInfo")) return *status;
  checkOptions(options);

  asyncfem::MeshReadReport report;
  std::string source = options.input;
  TetMesh mesh;
  if (!options.generate.empty()) {
    report.format = "generated";
    mesh = generateMesh(options, source);
  } else {
    asyncfem::MeshReadOptions readOptions;
    if (!options.defaultMaterial.empty()) {
      readOptions.defaultMaterial = asyncfem::Material{"default", options.defaultMaterial[0],
                                                       options.defaultMaterial[1], options.defaultMaterial[2]};
    }
    mesh = asyncfem::readMesh(options.input, readOptions, &report);
  }
  if (options.hexToTets) {
    if (!mesh.isHexahedral()) throw asyncfem::Error("--hex-to-tets: " + source + " holds tetrahedra already");
    report.warnings.push_back("split " + std::to_string(mesh.numElements()) + " hexahedra into " +
                              std::to_string(6 * mesh.numElements()) + " tetrahedra (--hex-to-tets)");
    mesh = asyncfem::hexahedraToTetrahedra(mesh);
  }
  for (const std::string& rename : options.renames) {
    const auto [from, to] = splitRename(rename);
    mesh.renameSet(from, to);
  }
  for (const std::string& warning : report.warnings) std::cerr << "meshInfo: warning: " << warning << '\n';

  const nlohmann::json description = describe(mesh, source, report, options.angleThreshold);
  if (options.json) {
    std::cout << description.dump(2) << '\n';
  } else {
    printText(description);
  }
  if (!options.output.empty()) {
    if (std::filesystem::path(options.output).extension() == ".veg") {
      asyncfem::writeVeg(options.output, mesh);
    } else {
      asyncfem::writeVtu(options.output, mesh);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  return asyncfem::cli::run("meshInfo", [&] { return run(argc, argv); });
}
