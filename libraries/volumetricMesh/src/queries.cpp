// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

namespace asyncfem {

double signedElementVolume(const TetMesh& mesh, int e) {
  if (mesh.isHexahedral()) return hexahedron::signedVolume(mesh.hexahedronRestPositions(e));
  const Eigen::Matrix<double, 3, 4> x = mesh.elementRestPositions(e);
  Eigen::Matrix3d edges;
  edges << x.col(1) - x.col(0), x.col(2) - x.col(0), x.col(3) - x.col(0);
  return edges.determinant() / 6.0;
}

Eigen::VectorXd elementVolumes(const TetMesh& mesh) {
  Eigen::VectorXd volumes(mesh.numElements());
  for (int e = 0; e < mesh.numElements(); ++e) volumes[e] = std::abs(signedElementVolume(mesh, e));
  return volumes;
}

double totalVolume(const TetMesh& mesh) { return elementVolumes(mesh).sum(); }

double totalMass(const TetMesh& mesh) {
  double mass = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    mass += mesh.elementMaterial(e).density * std::abs(signedElementVolume(mesh, e));
  }
  return mass;
}

namespace {

// Faces of a positively oriented tet (v0..v3) with outward normals (b-a)x(c-a).
constexpr std::array<std::array<int, 3>, 4> kTetFaces{{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};

/// The (element, local face) pairs of the faces that belong to one element only, in
/// element order. Faces are the tetrahedra's triangles or the hexahedra's quadrilaterals
/// (keyed by their sorted vertex ids; a triangle's key ends with INT_MAX).
std::vector<std::pair<int, int>> unsharedFaces(const TetMesh& mesh) {
  struct Face {
    std::array<int, 4> key;  // sorted vertex ids
    int element;
    int local;
  };
  const bool hexahedra = mesh.isHexahedral();
  const int facesPerElement = hexahedra ? 6 : 4;
  const int cornersPerFace = hexahedra ? 4 : 3;
  const auto connectivity = mesh.connectivity();
  std::vector<Face> faces;
  faces.reserve(static_cast<std::size_t>(facesPerElement) * static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (int f = 0; f < facesPerElement; ++f) {
      constexpr int kNone = std::numeric_limits<int>::max();
      std::array<int, 4> key{kNone, kNone, kNone, kNone};
      for (int a = 0; a < cornersPerFace; ++a) {
        const int local = hexahedra ? hexahedron::kFaces[static_cast<std::size_t>(f)][static_cast<std::size_t>(a)]
                                    : kTetFaces[static_cast<std::size_t>(f)][static_cast<std::size_t>(a)];
        key[static_cast<std::size_t>(a)] = connectivity(local, e);
      }
      std::sort(key.begin(), key.end());
      faces.push_back({key, e, f});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) {
    return a.key != b.key ? a.key < b.key : (a.element != b.element ? a.element < b.element : a.local < b.local);
  });
  std::vector<std::pair<int, int>> boundary;
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j - i == 1) boundary.emplace_back(faces[i].element, faces[i].local);
    i = j;
  }
  std::sort(boundary.begin(), boundary.end());
  return boundary;
}

}  // namespace

std::vector<std::array<int, 3>> boundaryTriangles(const TetMesh& mesh) {
  const std::vector<std::pair<int, int>> boundary = unsharedFaces(mesh);
  std::vector<std::array<int, 3>> triangles;
  if (mesh.isHexahedral()) {
    // Readers keep hexahedra positively oriented; each quadrilateral a b c d gives a b c and a c d.
    triangles.reserve(2 * boundary.size());
    for (const auto& [e, f] : boundary) {
      const auto& local = hexahedron::kFaces[static_cast<std::size_t>(f)];
      const auto h = mesh.connectivity().col(e);
      triangles.push_back({h[local[0]], h[local[1]], h[local[2]]});
      triangles.push_back({h[local[0]], h[local[2]], h[local[3]]});
    }
    return triangles;
  }
  triangles.reserve(boundary.size());
  for (const auto& [e, f] : boundary) {
    const Eigen::Vector4i t = mesh.element(e);
    const auto& local = kTetFaces[static_cast<std::size_t>(f)];
    std::array<int, 3> tri{t[local[0]], t[local[1]], t[local[2]]};
    // An element stored with negative orientation has every face turned inward.
    if (signedElementVolume(mesh, e) < 0.0) std::swap(tri[1], tri[2]);
    triangles.push_back(tri);
  }
  return triangles;
}

VertexElementAdjacency vertexElementAdjacency(const TetMesh& mesh) {
  VertexElementAdjacency adjacency;
  adjacency.offsets.assign(static_cast<std::size_t>(mesh.numVertices()) + 1, 0);
  const auto elements = mesh.connectivity();
  const int corners = mesh.verticesPerElement();
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < corners; ++a) ++adjacency.offsets[static_cast<std::size_t>(elements(a, e)) + 1];
  for (std::size_t v = 1; v < adjacency.offsets.size(); ++v) adjacency.offsets[v] += adjacency.offsets[v - 1];
  adjacency.elements.resize(static_cast<std::size_t>(adjacency.offsets.back()));
  std::vector<int> fill(adjacency.offsets.begin(), adjacency.offsets.end() - 1);
  // Visiting elements in increasing order leaves each vertex's list ascending.
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < corners; ++a)
      adjacency.elements[static_cast<std::size_t>(fill[static_cast<std::size_t>(elements(a, e))]++)] = e;
  return adjacency;
}

BoundingBox boundingBox(const TetMesh& mesh, const Eigen::VectorXd& displacement) {
  if (displacement.size() != 0 && displacement.size() != mesh.numDofs()) {
    throw ValidationError("boundingBox: displacement has " + std::to_string(displacement.size()) +
                          " entries, expected 0 or " + std::to_string(mesh.numDofs()));
  }
  if (mesh.numVertices() == 0) return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  Eigen::Matrix3Xd x = mesh.restPositions();
  if (displacement.size() != 0) x += Eigen::Map<const Eigen::Matrix3Xd>(displacement.data(), 3, mesh.numVertices());
  return {x.rowwise().minCoeff(), x.rowwise().maxCoeff()};
}

ElementQuality elementQuality(const TetMesh& mesh, int e) {
  mesh.requireTetrahedra("elementQuality (dihedral angles; hexahedra: hexahedronQuality)");
  if (e < 0 || e >= mesh.numElements())
    throw ValidationError("elementQuality: element " + std::to_string(e) + " out of range");
  const Eigen::Matrix<double, 3, 4> x = mesh.elementRestPositions(e);
  static constexpr std::array<std::array<int, 4>, 6> kEdges{
      {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}}};
  ElementQuality q;
  q.minDihedralAngle = std::numeric_limits<double>::infinity();
  q.maxDihedralAngle = 0.0;
  double longestEdge = 0.0;
  for (const auto& edge : kEdges) {
    // Interior angle between the two faces at edge (i, j): project the two other
    // vertices onto the plane normal to the edge and measure the angle between them.
    const Eigen::Vector3d xi = x.col(edge[0]);
    const Eigen::Vector3d along = x.col(edge[1]) - xi;
    longestEdge = std::max(longestEdge, along.norm());
    const Eigen::Vector3d direction = along.normalized();
    Eigen::Vector3d u = x.col(edge[2]) - xi;
    Eigen::Vector3d w = x.col(edge[3]) - xi;
    u -= u.dot(direction) * direction;
    w -= w.dot(direction) * direction;
    const double angle = std::atan2(u.cross(w).norm(), u.dot(w));
    q.minDihedralAngle = std::min(q.minDihedralAngle, angle);
    q.maxDihedralAngle = std::max(q.maxDihedralAngle, angle);
  }
  // Inradius r = 3V / (total face area); the regular tetrahedron of edge a has r = a / (2 sqrt 6).
  double area = 0.0;
  static constexpr std::array<std::array<int, 3>, 4> kFaces{{{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};
  for (const auto& f : kFaces) area += 0.5 * (x.col(f[1]) - x.col(f[0])).cross(x.col(f[2]) - x.col(f[0])).norm();
  const double volume = std::abs(signedElementVolume(mesh, e));
  const double inradius = area > 0.0 ? 3.0 * volume / area : 0.0;
  q.aspectRatio =
      inradius > 0.0 ? longestEdge / (2.0 * std::sqrt(6.0) * inradius) : std::numeric_limits<double>::infinity();
  return q;
}

std::vector<ElementQuality> elementQualities(const TetMesh& mesh) {
  std::vector<ElementQuality> qualities;
  qualities.reserve(static_cast<std::size_t>(mesh.numElements()));
  for (int e = 0; e < mesh.numElements(); ++e) qualities.push_back(elementQuality(mesh, e));
  return qualities;
}

QualitySummary summarizeQuality(const TetMesh& mesh, double thresholdDegrees) {
  QualitySummary s;
  s.thresholdDegrees = thresholdDegrees;
  if (mesh.numElements() == 0) return s;
  const double toDegrees = 180.0 / std::numbers::pi;
  s.minDihedralDegrees = std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (const ElementQuality& q : elementQualities(mesh)) {
    const double smallest = q.minDihedralAngle * toDegrees;
    s.minDihedralDegrees = std::min(s.minDihedralDegrees, smallest);
    s.maxDihedralDegrees = std::max(s.maxDihedralDegrees, q.maxDihedralAngle * toDegrees);
    sum += smallest;
    if (smallest < thresholdDegrees) ++s.elementsBelowThreshold;
    s.worstAspectRatio = std::max(s.worstAspectRatio, q.aspectRatio);
  }
  s.meanMinDihedralDegrees = sum / mesh.numElements();
  return s;
}

HexahedronQuality hexahedronQuality(const TetMesh& mesh, int e) {
  if (e < 0 || e >= mesh.numElements()) {
    throw ValidationError("hexahedronQuality: element " + std::to_string(e) + " out of range");
  }
  const Eigen::Matrix<double, 3, 8> x = mesh.hexahedronRestPositions(e);
  const Eigen::Matrix<double, 8, 1> scaled = hexahedron::cornerScaledJacobians(x);
  HexahedronQuality q;
  q.minScaledJacobian = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 8; ++a) {
    // NaN (an edge of zero length) counts as the worst value, 0.
    const double value = std::isnan(scaled[a]) ? 0.0 : scaled[a];
    if (value < q.minScaledJacobian) {
      q.minScaledJacobian = value;
      q.worstCorner = a;
    }
  }
  double shortest = std::numeric_limits<double>::infinity();
  double longest = 0.0;
  for (const auto& face : hexahedron::kFaces) {
    for (std::size_t a = 0; a < 4; ++a) {
      const double length = (x.col(face[a]) - x.col(face[(a + 1) % 4])).norm();
      shortest = std::min(shortest, length);
      longest = std::max(longest, length);
    }
  }
  q.edgeRatio = shortest > 0.0 ? longest / shortest : std::numeric_limits<double>::infinity();
  return q;
}

HexahedronQualitySummary summarizeHexahedronQuality(const TetMesh& mesh) {
  (void)mesh.hexahedra();  // throws, naming the kind, on a tetrahedral mesh
  HexahedronQualitySummary s;
  if (mesh.numElements() == 0) return s;
  s.minScaledJacobian = std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const HexahedronQuality q = hexahedronQuality(mesh, e);
    s.minScaledJacobian = std::min(s.minScaledJacobian, q.minScaledJacobian);
    sum += q.minScaledJacobian;
    s.worstEdgeRatio = std::max(s.worstEdgeRatio, q.edgeRatio);
    if (q.minScaledJacobian <= 0.0) s.invertedElements.push_back(e);
  }
  s.meanMinScaledJacobian = sum / mesh.numElements();
  return s;
}

std::vector<int> unusedVertices(const TetMesh& mesh) {
  std::vector<char> used(static_cast<std::size_t>(mesh.numVertices()), 0);
  for (const int v : mesh.connectivity().reshaped()) used[static_cast<std::size_t>(v)] = 1;
  std::vector<int> unused;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (!used[v]) unused.push_back(static_cast<int>(v));
  return unused;
}

}  // namespace asyncfem
