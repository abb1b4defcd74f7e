// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace asyncfem {

/// Writes the mesh as Vega .veg: vertices, TET elements, one *MATERIAL per material,
/// one *SET per element set, one *VERTEXSET per vertex set, and one *REGION line per
/// material naming a set with exactly that material's elements (an existing set, or an
/// added `__material_<name>` set that readVeg does not keep), so that
/// readVeg(writeVeg(m)) reproduces m exactly: every double is printed in the shortest form
/// that reads back to the same bits (at most 17 significant digits). This holds for
/// meshes whose elements are positively oriented and non-degenerate (readers reorient
/// or reject the others). Names must be single tokens (no spaces, commas or '#'), else
/// ValidationError. Writes to PATH.tmp and renames it, so a failure never leaves a
/// half-written file; asyncfem::Error if the file cannot be written.
void writeVeg(const std::filesystem::path& path, const TetMesh& mesh);

/// A named per-vertex (or per-element) array to add to a .vtu file.
struct VtuArray {
  std::string name;
  int components = 1;                ///< 1 (scalar) or 3 (vector)
  std::vector<double> values;        ///< components * count values, interleaved
};

/// Writes an unstructured-grid VTK XML file (ASCII) that ParaView opens: points at
/// restPositions + displacement (displacement: empty for the rest shape, or 3n stacked
/// x y z per vertex, then also written as point array "displacement"), tetrahedra
/// (VTK type 10), a per-cell Int32 "material" array (material index), and the given
/// point and cell arrays (ValidationError if a size or component count is wrong).
void writeVtu(const std::filesystem::path& path, const TetMesh& mesh,
              const Eigen::VectorXd& displacement = {}, const std::vector<VtuArray>& pointArrays = {},
              const std::vector<VtuArray>& cellArrays = {});

}  // namespace asyncfem
