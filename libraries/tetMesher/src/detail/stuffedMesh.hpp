// SPDX-License-Identifier: BSD-3-Clause
// Internal to the tetMesher library: steps 4 to 6 of isosurface stuffing, on any lattice.
#pragma once

#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <vector>

#include "detail/lattice.hpp"
#include "detail/latticeCrossings.hpp"

namespace asyncfem::detail {

/// The stencils over every lattice tetrahedron, then the optional pinch repair (warped
/// vertices on pinched boundary edges go back to the lattice, with the sign of their value,
/// and the stencils run again), the angle guard (an Error naming the worst element), the
/// checks (options.check) and the report. `values` are f at the lattice vertices.
/// ValidationError when no element is left.
template <StuffingLattice Lattice>
TetMesh assembleStuffedMesh(const Lattice& lattice, const std::vector<double>& values, LatticeCrossings& crossings,
                            double spacing, const MesherOptions& options, StuffingReport* report);

}  // namespace asyncfem::detail
