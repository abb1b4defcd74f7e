// SPDX-License-Identifier: BSD-3-Clause
// Format dispatch and the .bou reader; the mesh readers live in detail/*Reader.cpp.
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <string>
#include <vector>

#include "detail/textInput.hpp"

namespace asyncfem {

TetMesh readMesh(const std::filesystem::path& path, const MeshReadOptions& options, MeshReadReport* report) {
  const std::string extension = path.extension().string();
  if (detail::equalsIgnoreCase(extension, ".veg")) return readVeg(path, options, report);
  if (detail::equalsIgnoreCase(extension, ".node") || detail::equalsIgnoreCase(extension, ".ele")) {
    return readTetGen(path, options, report);
  }
  if (detail::equalsIgnoreCase(extension, ".msh")) return readGmsh(path, options, report);
  // A TetGen base name ("cube" for cube.node + cube.ele; "cube.1" for TetGen's cube.1.*).
  std::filesystem::path node = path;
  node += ".node";
  std::error_code ignored;
  if (std::filesystem::is_regular_file(node, ignored)) return readTetGen(node, options, report);
  const std::string expected = "a .veg, .node, .ele or .msh file, or the base name of a TetGen .node/.ele pair";
  for (const char* surface : {".off", ".stl", ".obj", ".ply", ".gltf", ".glb", ".fbx", ".dae", ".3ds"}) {
    if (detail::equalsIgnoreCase(extension, surface)) {
      throw Error("cannot read mesh '" + path.string() + "': " + extension +
                  " is a surface format, and a simulation needs a tetrahedral mesh: make one with tetMesher (" +
                  "tetMesher " + path.string() + " --output " + path.stem().string() +
                  ".veg; docs/tet-mesher.md), then give " + expected);
    }
  }
  if (extension.empty()) {
    throw Error("cannot read mesh '" + path.string() + "': there is no TetGen pair '" + node.string() + "' + '" +
                path.string() + ".ele' (a name without an extension is taken as a TetGen base name); give " + expected);
  }
  throw Error("cannot read mesh '" + path.string() + "': unknown extension '" + extension + "' (expected " + expected +
              ")");
}

TetMesh readMeshCollectingWarnings(const std::filesystem::path& path, std::vector<std::string>& warnings,
                                   const MeshReadOptions& options) {
  MeshReadReport report;
  TetMesh mesh = readMesh(path, options, &report);
  for (const std::string& warning : report.warnings) warnings.push_back(path.string() + ": " + warning);
  return mesh;
}

std::vector<int> readBou(const std::filesystem::path& path, int numVertices) {
  if (numVertices < 0) throw Error("readBou: negative vertex count for '" + path.string() + "'");
  const detail::FlatText flat = detail::loadFlatText(path, false);
  detail::LineCursor cursor(flat, true);
  std::vector<int> vertices;
  while (cursor.next()) {
    for (const std::string_view token : detail::splitTokens(cursor.line(), true)) {
      const long long id = detail::integerAt(cursor, token, "fixed vertex");
      if (id < 1 || id > numVertices) {
        cursor.fail("fixed vertex " + std::to_string(id) + " is outside [1, " + std::to_string(numVertices) + "]");
      }
      vertices.push_back(static_cast<int>(id - 1));
    }
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  return vertices;
}

}  // namespace asyncfem
