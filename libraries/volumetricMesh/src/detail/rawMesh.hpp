// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <array>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <map>
#include <string>
#include <vector>

#include "detail/textInput.hpp"

namespace asyncfem::detail {

/// What a reader has parsed before the checks that need the whole mesh (orientation,
/// degeneracy, materials, unused vertices). Ids in the file's own numbering are kept so
/// messages name elements and vertices as the user sees them.
struct RawMesh {
  ElementKind kind = ElementKind::tetrahedron;
  std::vector<double> positions;              ///< x y z per vertex
  std::vector<long long> vertexFileIds;       ///< id of each vertex in the file
  std::vector<std::array<int, 4>> elements;   ///< tetrahedra: 0-based vertex ids
  std::vector<std::array<int, 8>> hexahedra;  ///< hexahedra: 0-based vertex ids (VTK order)
  /// Vega CUBIC files: every hexahedron must be an axis-aligned cube of one size in
  /// Vega's vertex order (Vega's elements assume it without checking).
  bool vegaCubes = false;
  std::vector<Location> elementLocations;  ///< where each element was read
  std::vector<long long> elementFileIds;   ///< id of each element in the file
  std::vector<Material> materials;
  std::vector<int> elementMaterials;  ///< index into materials, -1 for none yet
  std::map<std::string, std::vector<int>> elementSets;
  std::map<std::string, std::vector<int>> vertexSets;

  std::size_t numElements() const { return kind == ElementKind::hexahedron ? hexahedra.size() : elements.size(); }
};

/// What to do with elements that have no material after reading.
enum class MissingMaterialPolicy {
  Error,          ///< .veg: an element outside every *REGION is an error
  FormatDefault,  ///< TetGen, Gmsh: no materials in the format, use the documented default
};

/// The default material of formats that carry none (documented in docs/file-formats.md).
Material formatDefaultMaterial();

/// Throws a ParseError at the cursor's line unless density > 0, E > 0, -1 < nu < 0.5.
void checkMaterialAt(const LineCursor& cursor, const Material& material);

/// Applies the material policy, checks every element for degeneracy and orientation
/// (reorienting when options allow), reports unused vertices, and builds the TetMesh.
/// The hexahedra of raw, checked (hexChecks.cpp): distinct vertex positions, a positive
/// Jacobian at every corner (an element negative at all eight is reoriented by swapping its
/// bottom and top faces when options allow, counted in report) and, with raw.vegaCubes,
/// Vega's cube shape. Errors name the element, its line and the corner.
HexElements checkedHexahedra(const RawMesh& raw, const Eigen::Matrix3Xd& positions, const LineCursor& cursor,
                             const MeshReadOptions& options, MeshReadReport& report);

TetMesh finishMesh(RawMesh raw, const LineCursor& cursor, const MeshReadOptions& options, MeshReadReport& report,
                   MissingMaterialPolicy policy);

}  // namespace asyncfem::detail
