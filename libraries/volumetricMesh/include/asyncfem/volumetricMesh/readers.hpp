// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// What the caller wants a reader to do in the cases the format leaves open.
struct MeshReadOptions {
  /// Material for elements that no *REGION (or physical group) covers. Without it such
  /// elements are an error naming the first one.
  std::optional<Material> defaultMaterial;
  /// Elements with negative signed volume are reoriented (two vertices swapped) and
  /// counted in MeshReadReport::reorientedElements. With false they are an error.
  bool reorientInvertedElements = true;
  /// An element whose |signed volume| is below this fraction of (mean edge length)^3
  /// is degenerate: an error naming the element and its line.
  double degenerateVolumeTolerance = 1e-12;
};

/// What a reader noticed without failing; utilities print it.
struct MeshReadReport {
  std::string format;                   ///< "veg", "tetgen", "gmsh 2.2", "gmsh 4.1"
  std::vector<std::string> warnings;    ///< e.g. unused vertices, ignored element types
  int reorientedElements = 0;
  int unusedVertices = 0;
  int ignoredElements = 0;              ///< non-tet elements skipped (Gmsh points/lines/triangles)
};

/// Reads a tetrahedral mesh, choosing the reader from the extension: .veg; .node/.ele
/// (TetGen; either file names the pair); .msh (Gmsh 2.2 or 4.1 ASCII).
/// Errors: asyncfem::ParseError "FILE:LINE: message" for malformed input,
/// asyncfem::Error for unreadable files or unknown extensions.
TetMesh readMesh(const std::filesystem::path& path, const MeshReadOptions& options = {},
                 MeshReadReport* report = nullptr);

TetMesh readVeg(const std::filesystem::path& path, const MeshReadOptions& options = {},
                MeshReadReport* report = nullptr);
/// path may be the .node file, the .ele file or the common base name.
TetMesh readTetGen(const std::filesystem::path& path, const MeshReadOptions& options = {},
                   MeshReadReport* report = nullptr);
TetMesh readGmsh(const std::filesystem::path& path, const MeshReadOptions& options = {},
                 MeshReadReport* report = nullptr);

/// Reads a Vega .bou file: 1-based vertex ids separated by commas/whitespace, '#'
/// comments, trailing commas allowed; returns sorted unique 0-based ids. Ids outside
/// [1, numVertices] are a ParseError naming file and line.
std::vector<int> readBou(const std::filesystem::path& path, int numVertices);

}  // namespace asyncfem
