// SPDX-License-Identifier: BSD-3-Clause
#include "detail/stuffedMesh.hpp"

#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <map>
#include <sstream>
#include <string>
#include <utility>

#include "detail/bccLattice.hpp"
#include "detail/gradedLattice.hpp"
#include "detail/stencils.hpp"

namespace asyncfem::detail {

namespace {

/// Boundary edges (vertex pairs) shared by more than two boundary triangles.
std::vector<std::pair<int, int>> nonManifoldBoundaryEdges(const TetMesh& mesh) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& t : boundaryTriangles(mesh))
    for (int i = 0; i < 3; ++i) {
      const int a = t[static_cast<std::size_t>(i)], b = t[static_cast<std::size_t>((i + 1) % 3)];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::pair<int, int>> edges;
  for (const auto& [edge, uses] : count)
    if (uses > 2) edges.push_back(edge);
  return edges;
}

void throwNoElement(const std::vector<double>& values, double spacing) {
  std::ostringstream message;
  message << "stuffIsosurface: no element: no lattice vertex lies inside the solid at spacing " << spacing;
  if (*std::min_element(values.begin(), values.end()) >= 0.0)
    message << " (f >= 0 at every one: the solid is thinner than the lattice everywhere, or empty, or f is not "
               "negative inside); try a spacing below "
            << 0.5 * spacing;
  throw ValidationError(message.str());
}

TetMesh toTetMesh(const StencilOutput& stencils, const Material& material) {
  Eigen::Matrix3Xd positions(3, static_cast<Eigen::Index>(stencils.positions.size()));
  for (std::size_t v = 0; v < stencils.positions.size(); ++v)
    positions.col(static_cast<Eigen::Index>(v)) = stencils.positions[v];
  Eigen::Matrix4Xi elements(4, static_cast<Eigen::Index>(stencils.elements.size()));
  for (std::size_t e = 0; e < stencils.elements.size(); ++e)
    elements.col(static_cast<Eigen::Index>(e)) = stencils.elements[e];
  return TetMesh(std::move(positions), std::move(elements), {material}, std::vector<int>(stencils.elements.size(), 0));
}

/// Where the surface is thinner than the lattice resolves, two warped vertices can pinch two
/// sheets of the boundary together along an edge: the warped lattice vertices on such edges.
std::vector<long long> pinchedWarpedVertices(const TetMesh& mesh, const StencilOutput& stencils,
                                             const LatticeCrossings& crossings) {
  std::vector<long long> pinched;
  for (const auto& [a, b] : nonManifoldBoundaryEdges(mesh)) {
    for (int v : {a, b}) {
      const long long source = stencils.sources[static_cast<std::size_t>(v)];
      if (source >= 0 && crossings.warped.count(source) > 0) pinched.push_back(source);
    }
  }
  return pinched;
}

/// Moves pinched vertices back to their lattice positions (their cut points are known from
/// step 2), which restores the marching-tetrahedra structure there; returns how many moved.
int unwarp(const std::vector<long long>& pinched, const std::vector<double>& values, LatticeCrossings& crossings) {
  int moved = 0;
  for (long long v : pinched) {
    if (crossings.warped.erase(v) > 0) {
      crossings.signs[static_cast<std::size_t>(v)] = signOf(values[static_cast<std::size_t>(v)]);
      ++moved;
    }
  }
  return moved;
}

/// Not the input's fault: the stencils guarantee 10.78 degrees for any function.
void throwBelowAngleBound(const TetMesh& mesh, double minDihedralDegrees, double spacing,
                          const MesherOptions& options) {
  const std::vector<ElementQuality> qualities = elementQualities(mesh);
  int worst = 0;
  for (int e = 1; e < mesh.numElements(); ++e)
    if (qualities[static_cast<std::size_t>(e)].minDihedralAngle <
        qualities[static_cast<std::size_t>(worst)].minDihedralAngle)
      worst = e;
  const Eigen::Vector3d centre = mesh.elementRestPositions(worst).rowwise().mean();
  std::ostringstream message;
  message << "stuffIsosurface: internal error: element " << worst << " near (" << centre.x() << ", " << centre.y()
          << ", " << centre.z() << ") has a dihedral angle of " << minDihedralDegrees
          << " degrees, below the guaranteed " << options.minDihedralDegrees << " (spacing " << spacing
          << ", alphaLong " << options.alphaLong << ", alphaShort " << options.alphaShort
          << "; the bound holds for the default alphas); the mesh was not returned";
  throw Error(message.str());
}

void fillReport(const TetMesh& mesh, const MeshQuality& quality, const StencilOutput& stencils,
                const LatticeCrossings& crossings, long long latticeVertices, long long latticeTetrahedra, int unwarped,
                StuffingReport& report) {
  report.latticeVertices = latticeVertices;
  report.latticeTetrahedra = latticeTetrahedra;
  report.cutPoints = stencils.cutPointsUsed;
  report.warpedVertices = static_cast<int>(crossings.warped.size());
  report.unwarpedVertices = unwarped;
  report.elements = mesh.numElements();
  report.vertices = mesh.numVertices();
  report.minDihedralDegrees = quality.minDihedralDegrees;
  report.maxDihedralDegrees = quality.maxDihedralDegrees;
  report.pinchedBoundaryEdges = static_cast<int>(nonManifoldBoundaryEdges(mesh).size());
}

/// The pinch repair gives up after this many rounds and returns the mesh as it is.
constexpr int kMaxPinchRepairRounds = 32;

}  // namespace

template <StuffingLattice Lattice>
TetMesh assembleStuffedMesh(const Lattice& lattice, const std::vector<double>& values, LatticeCrossings& crossings,
                            double spacing, const MesherOptions& options, StuffingReport* report) {
  int unwarped = 0;
  for (int attempt = 0;; ++attempt) {
    StencilBuilder<Lattice> builder(lattice, crossings);
    // Most lattice tetrahedra have no inside vertex: skip them before the stencil call.
    const long long latticeTetrahedra = lattice.forEachTetrahedron([&](const std::array<long long, 4>& tet) {
      for (long long v : tet) {
        if (crossings.signs[static_cast<std::size_t>(v)] < 0) {
          builder.fill(tet);
          return;
        }
      }
    });
    const StencilOutput& stencils = builder.output();
    if (stencils.elements.empty()) throwNoElement(values, spacing);
    TetMesh mesh = toTetMesh(stencils, options.material);
    if (options.repairPinches && attempt < kMaxPinchRepairRounds) {
      const std::vector<long long> pinched = pinchedWarpedVertices(mesh, stencils, crossings);
      if (!pinched.empty()) {
        unwarped += unwarp(pinched, values, crossings);
        continue;
      }
    }
    const MeshQuality quality = meshQuality(mesh);
    if (options.minDihedralDegrees > 0.0 && unwarped == 0 && quality.minDihedralDegrees < options.minDihedralDegrees)
      throwBelowAngleBound(mesh, quality.minDihedralDegrees, spacing, options);
    if (options.check) validateTetMesh(mesh, "stuffIsosurface (spacing " + std::to_string(spacing) + ")");
    if (report != nullptr)
      fillReport(mesh, quality, stencils, crossings, static_cast<long long>(values.size()), latticeTetrahedra, unwarped,
                 *report);
    return mesh;
  }
}

template TetMesh assembleStuffedMesh(const BccLattice&, const std::vector<double>&, LatticeCrossings&, double,
                                     const MesherOptions&, StuffingReport*);
template TetMesh assembleStuffedMesh(const GradedLattice&, const std::vector<double>&, LatticeCrossings&, double,
                                     const MesherOptions&, StuffingReport*);

}  // namespace asyncfem::detail
