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
  std::string format;                 ///< "veg", "tetgen", "gmsh 2.2", "gmsh 4.1"
  std::vector<std::string> warnings;  ///< e.g. unused vertices, ignored element types
  int reorientedElements = 0;
  int unusedVertices = 0;
  int ignoredElements = 0;  ///< non-tet elements skipped (Gmsh points/lines/triangles)
};

/// Reads a tetrahedral mesh, choosing the reader from the extension: .veg; .node/.ele
/// (TetGen; either file names the pair, and so does their base name: "cube" or "cube.1"
/// for cube.node + cube.ele or cube.1.node + cube.1.ele); .msh (Gmsh 2.2 or 4.1 ASCII).
/// Errors: asyncfem::ParseError "FILE:LINE: message" for malformed input,
/// asyncfem::Error for unreadable files or unknown extensions.
TetMesh readMesh(const std::filesystem::path& path, const MeshReadOptions& options = {},
                 MeshReadReport* report = nullptr);

/// readMesh for programs that print what the reader noticed: appends each of the report's
/// warnings to warnings as "<path>: <warning>".
TetMesh readMeshCollectingWarnings(const std::filesystem::path& path, std::vector<std::string>& warnings,
                                   const MeshReadOptions& options = {});

/// Vega .veg, tetrahedral subset (docs/file-formats.md): *VERTICES, *ELEMENTS (TET only),
/// *MATERIAL with `ENU, density, E, nu`, *SET (1-based element ids), *REGION `set, material`
/// (later lines win where sets overlap), *INCLUDE (relative to the including file, also
/// inside a *SET body), '#' comments, and the extension *VERTEXSET (1-based vertex ids,
/// written by writeVeg). *SETs become element sets, except those named `__material_*`,
/// which writeVeg adds only to carry a material and which are used for *REGION alone.
TetMesh readVeg(const std::filesystem::path& path, const MeshReadOptions& options = {},
                MeshReadReport* report = nullptr);
/// TetGen .node/.ele; path may be the .node file, the .ele file or the common base name.
/// The first vertex index (0 or 1) sets the numbering of both files. Attributes and
/// boundary markers are checked and ignored; a region attribute r puts the element into
/// the element set "region_<r>". An optional .face file next to them (TetGen -f) gives the
/// vertex set "marker_<k>" of the vertices of the faces with boundary marker k != 0. 10-node tetrahedra keep their 4
/// corners; vertices used only as edge nodes are dropped (a warning says so). TetGen has no materials: elements get
/// options.defaultMaterial or else Material{"default", 1000, 1e6, 0.45} with a warning.
TetMesh readTetGen(const std::filesystem::path& path, const MeshReadOptions& options = {},
                   MeshReadReport* report = nullptr);
/// Gmsh .msh ASCII 2.2 or 4.1. Only 4-node tetrahedra (type 4) are read; other element
/// types are counted in MeshReadReport::ignoredElements with one warning. Node tags may be
/// any positive integers. A physical volume group becomes an element set named from
/// $PhysicalNames, or "physical_<tag>" without a name; a physical surface, curve or point
/// becomes a vertex set (its elements' nodes) named likewise, or "physical_surface_<tag>",
/// "physical_curve_<tag>", "physical_point_<tag>". Binary files and other versions are
/// ParseErrors. Materials as for readTetGen.
TetMesh readGmsh(const std::filesystem::path& path, const MeshReadOptions& options = {},
                 MeshReadReport* report = nullptr);

/// Reads a Vega .bou file: 1-based vertex ids separated by commas/whitespace, '#'
/// comments, trailing commas allowed; returns sorted unique 0-based ids. Ids outside
/// [1, numVertices] are a ParseError naming file and line.
std::vector<int> readBou(const std::filesystem::path& path, int numVertices);

}  // namespace asyncfem
