// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace asyncfem {

/// Writes the mesh as Vega .veg: vertices, TET elements, one *MATERIAL per material,
/// one *SET per element set plus one per material's elements, and *REGION lines, so
/// that readVeg(writeVeg(m)) reproduces m exactly (positions printed with 17
/// significant digits). Writes to a temporary file and renames it, so a failure never
/// leaves a half-written file.
void writeVeg(const std::filesystem::path& path, const TetMesh& mesh);

/// A named per-vertex (or per-element) array to add to a .vtu file.
struct VtuArray {
  std::string name;
  int components = 1;                ///< 1 (scalar) or 3 (vector)
  std::vector<double> values;        ///< components * count values, interleaved
};

/// Writes an unstructured-grid VTK XML file (ASCII) that ParaView opens: points at
/// restPositions + displacement (displacement may be empty: rest shape), tetrahedra,
/// a per-cell "material" array, and the given point and cell arrays.
void writeVtu(const std::filesystem::path& path, const TetMesh& mesh,
              const Eigen::VectorXd& displacement = {}, const std::vector<VtuArray>& pointArrays = {},
              const std::vector<VtuArray>& cellArrays = {});

}  // namespace asyncfem
