// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/volumetricMesh/tetMesh.hpp>

namespace asyncfem {

/// The tetrahedral mesh of a hexahedral one: each hexahedron split into six tetrahedra
/// (Kuhn / Freudenthal split around one body diagonal: one tetrahedron per order of
/// walking the three axes from one end of the diagonal to the other), on the same vertices,
/// each positively oriented. The diagonal of every hexahedron starts at its corner of
/// smallest x + y + z (the minimum corner of an axis-aligned cube, ties to the lower vertex
/// number), so every cube of an axis-aligned lattice uses the same direction and the
/// triangulations of shared faces match: the result is conforming. For other hexahedral
/// meshes the face diagonals are checked: a face two hexahedra share but split along
/// different diagonals is a ValidationError naming both hexahedra.
///
/// Tetrahedra 6 e .. 6 e + 5 come from hexahedron e and keep its material; element sets
/// map to the tetrahedra of their hexahedra; vertex sets are copied. Exact volumes: the
/// six tetrahedra of a parallelepiped fill it. A tetrahedral mesh is a ValidationError.
TetMesh hexahedraToTetrahedra(const TetMesh& mesh);

}  // namespace asyncfem
