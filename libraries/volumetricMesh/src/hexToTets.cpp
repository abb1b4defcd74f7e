// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/hexToTets.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace asyncfem {

namespace {

/// The corner of x (3 x 8) with the smallest x + y + z, ties to the lower vertex number.
int startCorner(const Eigen::Matrix<double, 3, 8>& x) {
  int best = 0;
  for (int a = 1; a < 8; ++a) {
    if (x.col(a).sum() < x.col(best).sum()) best = a;
  }
  return best;
}

/// The six tetrahedra (local vertex numbers) of the Kuhn split from corner start: one per
/// permutation of the axes, stepping along them in that order to the opposite corner.
std::array<std::array<int, 4>, 6> kuhnTetrahedra(int start) {
  static constexpr std::array<std::array<int, 3>, 6> kAxisOrders{
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  std::array<std::array<int, 4>, 6> tets{};
  for (std::size_t p = 0; p < 6; ++p) {
    int corner = start;
    tets[p][0] = corner;
    for (std::size_t s = 0; s < 3; ++s) {
      corner = hexahedron::flippedCorner(corner, 1 << kAxisOrders[p][s]);
      tets[p][s + 1] = corner;
    }
  }
  return tets;
}

double tetVolume(const Eigen::Matrix3Xd& x, const Eigen::Vector4i& t) {
  Eigen::Matrix3d edges;
  for (int a = 0; a < 3; ++a) edges.col(a) = x.col(t[a + 1]) - x.col(t[0]);
  return edges.determinant() / 6.0;
}

/// Records the diagonal that hexahedron e's split puts on each of its faces and throws
/// when a face shared with an earlier hexahedron got the other diagonal.
class FaceDiagonals {
 public:
  void add(int e, const Vector8i& h, int start) {
    for (const auto& face : hexahedron::kFaces) {
      std::array<int, 4> key{h[face[0]], h[face[1]], h[face[2]], h[face[3]]};
      std::sort(key.begin(), key.end());
      // Each split face holds start or the opposite corner; its diagonal runs through that
      // corner and the face's corner opposite it.
      int through = -1;
      for (std::size_t a = 0; a < 4; ++a) {
        if (face[a] == start || face[a] == hexahedron::flippedCorner(start, 7)) through = static_cast<int>(a);
      }
      const auto from = static_cast<std::size_t>(through);
      std::pair<int, int> diagonal{h[face[from]], h[face[(from + 2) % 4]]};
      if (diagonal.first > diagonal.second) std::swap(diagonal.first, diagonal.second);
      const auto [it, inserted] = faces_.emplace(key, std::make_pair(e, diagonal));
      if (!inserted && it->second.second != diagonal) {
        throw ValidationError("hexahedraToTetrahedra: hexahedra " + std::to_string(it->second.first) + " and " +
                              std::to_string(e) +
                              " share a face that their splits cut along different diagonals, so the tetrahedra "
                              "would not conform (the conversion needs a structured hexahedral mesh, such as "
                              "Vega's cubes)");
      }
    }
  }

 private:
  std::map<std::array<int, 4>, std::pair<int, std::pair<int, int>>> faces_;
};

}  // namespace

TetMesh hexahedraToTetrahedra(const TetMesh& mesh) {
  const HexElements& hexahedra = mesh.hexahedra();
  const int numHexahedra = mesh.numElements();
  Eigen::Matrix4Xi tets(4, 6 * static_cast<Eigen::Index>(numHexahedra));
  std::vector<int> materials(6 * static_cast<std::size_t>(numHexahedra));
  FaceDiagonals diagonals;
  for (int e = 0; e < numHexahedra; ++e) {
    const Vector8i h = hexahedra.col(e);
    const int start = startCorner(mesh.hexahedronRestPositions(e));
    diagonals.add(e, h, start);
    const auto local = kuhnTetrahedra(start);
    for (std::size_t k = 0; k < 6; ++k) {
      Eigen::Vector4i t;
      for (std::size_t a = 0; a < 4; ++a) t[static_cast<Eigen::Index>(a)] = h[local[k][a]];
      // Starting at a corner other than vertex 0 mirrors some axes, which turns half of the
      // tetrahedra over.
      if (tetVolume(mesh.restPositions(), t) < 0.0) std::swap(t[2], t[3]);
      const auto column = (6 * static_cast<Eigen::Index>(e)) + static_cast<Eigen::Index>(k);
      tets.col(column) = t;
      materials[static_cast<std::size_t>(column)] = mesh.elementMaterialIndex(e);
    }
  }
  TetMesh result(mesh.restPositions(), std::move(tets), mesh.materials(), std::move(materials));
  for (const auto& [name, members] : mesh.elementSets()) {
    std::vector<int> split;
    split.reserve(6 * members.size());
    for (int e : members)
      for (int k = 0; k < 6; ++k) split.push_back((6 * e) + k);
    result.setElementSet(name, std::move(split));
  }
  for (const auto& [name, members] : mesh.vertexSets()) result.setVertexSet(name, members);
  return result;
}

}  // namespace asyncfem
