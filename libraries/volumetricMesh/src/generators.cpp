// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>

namespace asyncfem {

namespace {

double signedVolume(const Eigen::Matrix3Xd& x, const Eigen::Vector4i& t) {
  const Eigen::Vector3d a = x.col(t[1]) - x.col(t[0]);
  const Eigen::Vector3d b = x.col(t[2]) - x.col(t[0]);
  const Eigen::Vector3d c = x.col(t[3]) - x.col(t[0]);
  return a.dot(b.cross(c)) / 6.0;
}

bool inside(const Eigen::Vector3d& p, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

}  // namespace

TetMesh makeBoxMesh(const BoxMeshSpec& spec) {
  const Eigen::Vector3i n = spec.cells;
  if ((n.array() < 1).any()) throw ValidationError("box mesh: every cell count must be >= 1");
  if (!(spec.size.array() > 0.0).all() || !spec.size.allFinite() || !spec.origin.allFinite()) {
    throw ValidationError("box mesh: size must be positive and finite");
  }
  const long long cellCount = static_cast<long long>(n.x()) * n.y() * n.z();
  if (cellCount * 6 > 200'000'000LL) throw ValidationError("box mesh: more than 2e8 elements requested");

  const int nx = n.x() + 1, ny = n.y() + 1, nz = n.z() + 1;
  auto vertexId = [&](int i, int j, int k) { return i + nx * (j + ny * k); };
  Eigen::Matrix3Xd x(3, nx * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        x.col(vertexId(i, j, k)) =
            spec.origin + spec.size.cwiseProduct(Eigen::Vector3d(double(i) / n.x(), double(j) / n.y(), double(k) / n.z()));

  // Freudenthal (Kuhn) split: one tet per permutation of the axes, walking from the
  // cell's low corner to its high corner. All cells use the same main diagonal, so the
  // triangulations of shared faces match.
  static constexpr std::array<std::array<int, 3>, 6> permutations{
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  Eigen::Matrix4Xi elements(4, cellCount * 6);
  int e = 0;
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i)
        for (const auto& p : permutations) {
          std::array<int, 3> c{i, j, k};
          Eigen::Vector4i t;
          t[0] = vertexId(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[static_cast<std::size_t>(p[static_cast<std::size_t>(s)])];
            t[s + 1] = vertexId(c[0], c[1], c[2]);
          }
          if (signedVolume(x, t) < 0.0) std::swap(t[2], t[3]);
          elements.col(e++) = t;
        }

  std::vector<Material> materials{spec.material};
  std::vector<int> elementMaterials(static_cast<std::size_t>(elements.cols()), 0);
  std::vector<std::vector<int>> regionElements(spec.regions.size());
  for (int el = 0; el < elements.cols(); ++el) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) centroid += 0.25 * x.col(elements(a, el));
    for (std::size_t r = 0; r < spec.regions.size(); ++r) {
      if (inside(centroid, spec.regions[r].min, spec.regions[r].max)) {
        // Later regions win the material; every containing region lists the element.
        elementMaterials[static_cast<std::size_t>(el)] = static_cast<int>(r) + 1;
        regionElements[r].push_back(el);
      }
    }
  }
  for (const BoxRegion& r : spec.regions) materials.push_back(r.material);

  TetMesh mesh(std::move(x), std::move(elements), std::move(materials), std::move(elementMaterials));
  for (std::size_t r = 0; r < spec.regions.size(); ++r) {
    std::vector<int> vertices;
    for (int el : regionElements[r])
      for (int a = 0; a < 4; ++a) vertices.push_back(mesh.elements()(a, el));
    mesh.setElementSet(spec.regions[r].name, regionElements[r]);
    mesh.setVertexSet(spec.regions[r].name, std::move(vertices));
  }
  const std::array<const char*, 6> faceNames{"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<int> low, high;
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const std::array<int, 3> c{i, j, k};
          const int last = n[axis];
          if (c[static_cast<std::size_t>(axis)] == 0) low.push_back(vertexId(i, j, k));
          if (c[static_cast<std::size_t>(axis)] == last) high.push_back(vertexId(i, j, k));
        }
    mesh.setVertexSet(faceNames[static_cast<std::size_t>(2 * axis)], std::move(low));
    mesh.setVertexSet(faceNames[static_cast<std::size_t>(2 * axis + 1)], std::move(high));
  }
  return mesh;
}

TetMesh makeBeamMesh(const BeamSpec& spec) {
  if (spec.cellsAlongLength < 1) throw ValidationError("beam: cellsAlongLength must be >= 1");
  if (!(spec.tipFraction >= 0.0 && spec.tipFraction < 1.0)) throw ValidationError("beam: tipFraction must be in [0, 1)");
  if (!(spec.length > 0 && spec.height > 0 && spec.depth > 0)) throw ValidationError("beam: dimensions must be positive");
  const double cell = spec.length / spec.cellsAlongLength;
  BoxMeshSpec box;
  box.size = Eigen::Vector3d(spec.length, spec.height, spec.depth);
  box.cells = Eigen::Vector3i(spec.cellsAlongLength, std::max(1, static_cast<int>(std::lround(spec.height / cell))),
                              std::max(1, static_cast<int>(std::lround(spec.depth / cell))));
  box.material = spec.body;
  const double tipStart = spec.length * (1.0 - spec.tipFraction);
  if (spec.tipFraction > 0.0) {
    box.regions.push_back({"tip", Eigen::Vector3d(tipStart, -1.0, -1.0),
                           Eigen::Vector3d(spec.length + 1.0, spec.height + 1.0, spec.depth + 1.0), spec.tip});
  }
  TetMesh mesh = makeBoxMesh(box);
  mesh.setVertexSet("root", mesh.vertexSet("xmin"));
  std::vector<int> bodyElements;
  const std::vector<int> tipElements = spec.tipFraction > 0.0 ? mesh.elementSet("tip") : std::vector<int>{};
  for (int e = 0, t = 0; e < mesh.numElements(); ++e) {
    if (t < static_cast<int>(tipElements.size()) && tipElements[static_cast<std::size_t>(t)] == e) {
      ++t;
      continue;
    }
    bodyElements.push_back(e);
  }
  mesh.setElementSet("body", std::move(bodyElements));
  return mesh;
}

}  // namespace asyncfem
