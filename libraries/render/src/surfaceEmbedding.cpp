// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/surfaceEmbedding.hpp>
#include <asyncfem/volumetricMesh/hexahedron.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <limits>
#include <string>

namespace asyncfem {

namespace {

/// Closest point to p on triangle (a, b, c), by the Voronoi region of p: the three
/// vertex regions, the three edge regions, or the face.
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a;
  const Eigen::Vector3d ac = c - a;
  const Eigen::Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    return a;
  }
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    return b;
  }
  const double vc = (d1 * d4) - (d3 * d2);
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    return a + (d1 / (d1 - d3)) * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    return c;
  }
  const double vb = (d5 * d2) - (d1 * d6);
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    return a + (d2 / (d2 - d6)) * ac;
  }
  const double va = (d3 * d6) - (d5 * d4);
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denominator = 1.0 / (va + vb + vc);
  return a + (vb * denominator) * ab + (vc * denominator) * ac;
}

/// Uniform grid of element bounding boxes for point location.
class ElementGrid {
 public:
  explicit ElementGrid(const TetMesh& mesh) : mesh_(mesh) {
    const Eigen::Vector3d upper = measureElements();
    chooseCells(upper);
    fillCells();
    visited_.assign(static_cast<std::size_t>(mesh.numElements()), -1);
  }

  /// The weights of p in element e (sum 1): barycentric coordinates in a tetrahedron, the
  /// eight trilinear shape functions at p's reference coordinates in a hexahedron.
  Eigen::VectorXd weights(int e, const Eigen::Vector3d& p) const {
    if (mesh_.isHexahedral()) {
      return hexahedron::shapeFunctions(hexahedron::referenceCoordinates(mesh_.hexahedronRestPositions(e), p));
    }
    const Eigen::Vector3d l = inverses_[static_cast<std::size_t>(e)] * (p - mesh_.restPosition(mesh_.elements()(0, e)));
    return Eigen::Vector4d(1.0 - l.sum(), l.x(), l.y(), l.z());
  }

  /// Non-negative exactly when p is in element e, larger deeper inside: the smallest
  /// barycentric coordinate, or 1 - max |xi_i| of the reference coordinates of a hexahedron.
  double insideScore(int e, const Eigen::Vector3d& p) const {
    if (mesh_.isHexahedral()) {
      return 1.0 - hexahedron::referenceCoordinates(mesh_.hexahedronRestPositions(e), p).lpNorm<Eigen::Infinity>();
    }
    return weights(e, p).minCoeff();
  }

  /// Euclidean distance from p to element e (0 inside): to the nearest of its boundary
  /// triangles (a hexahedron's quadrilateral a b c d as a b c and a c d, exact for planar faces).
  double distance(int e, const Eigen::Vector3d& p) const {
    if (insideScore(e, p) >= 0.0) {
      return 0.0;
    }
    double best = std::numeric_limits<double>::infinity();
    auto triangle = [&](int a, int b, int c) {
      const Eigen::Vector3d q = closestPointOnTriangle(p, vertex(e, a), vertex(e, b), vertex(e, c));
      best = std::min(best, (p - q).norm());
    };
    if (mesh_.isHexahedral()) {
      for (const auto& f : hexahedron::kFaces) {
        triangle(f[0], f[1], f[2]);
        triangle(f[0], f[2], f[3]);
      }
      return best;
    }
    constexpr int faces[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    for (const auto& f : faces) triangle(f[0], f[1], f[2]);
    return best;
  }

  /// The element containing p (largest insideScore among the candidates, ties to the lower
  /// id) or else the nearest one; its distance in *dist.
  int locate(const Eigen::Vector3d& p, int stamp, double* dist) {
    const Eigen::Vector3i center = cellOf(p);
    const int containing = containingElement(center, p);
    if (containing >= 0) {
      *dist = 0.0;
      return containing;
    }
    return nearestElement(center, p, stamp, dist);
  }

 private:
  Eigen::Vector3d vertex(int e, int a) const { return mesh_.restPosition(mesh_.elementVertex(e, a)); }

  /// Element boxes, the tetrahedra's inverse edge matrices, and lower_; returns the upper
  /// corner of all boxes.
  Eigen::Vector3d measureElements() {
    const int numElements = mesh_.numElements();
    lower_ = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d upper = -lower_;
    boxes_.resize(static_cast<std::size_t>(numElements));
    if (!mesh_.isHexahedral()) inverses_.resize(static_cast<std::size_t>(numElements));
    for (int e = 0; e < numElements; ++e) {
      BoundingBox& box = boxes_[static_cast<std::size_t>(e)];
      box = {vertex(e, 0), vertex(e, 0)};
      for (int a = 1; a < mesh_.verticesPerElement(); ++a) {
        box.min = box.min.cwiseMin(vertex(e, a));
        box.max = box.max.cwiseMax(vertex(e, a));
      }
      lower_ = lower_.cwiseMin(box.min);
      upper = upper.cwiseMax(box.max);
      if (mesh_.isHexahedral()) continue;
      Eigen::Matrix3d edges;
      edges << vertex(e, 1) - vertex(e, 0), vertex(e, 2) - vertex(e, 0), vertex(e, 3) - vertex(e, 0);
      inverses_[static_cast<std::size_t>(e)] = edges.inverse();
    }
    return upper;
  }

  /// Cell size and counts: about one element per cell, at most 256 cells per axis.
  void chooseCells(const Eigen::Vector3d& upper) {
    const Eigen::Vector3d extent = (upper - lower_).cwiseMax(1e-12 * std::max(1.0, (upper - lower_).norm()));
    cellSize_ = std::cbrt(extent.prod() / std::max(1, mesh_.numElements()));
    cellSize_ = std::max({cellSize_, extent.maxCoeff() / 256.0, 1e-300});
    for (int k = 0; k < 3; ++k) {
      cells_[k] = std::max(1, static_cast<int>(std::ceil(extent[k] / cellSize_)));
    }
  }

  /// Lists every element in each cell its box overlaps: counts in a first pass, fills in a second.
  void fillCells() {
    const int numElements = mesh_.numElements();
    std::vector<int> counts(static_cast<std::size_t>(cells_[0]) * cells_[1] * cells_[2] + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      for (int e = 0; e < numElements; ++e) {
        const Eigen::Vector3i lo = cellOf(boxes_[static_cast<std::size_t>(e)].min);
        const Eigen::Vector3i hi = cellOf(boxes_[static_cast<std::size_t>(e)].max);
        for (int i = lo.x(); i <= hi.x(); ++i) {
          for (int j = lo.y(); j <= hi.y(); ++j) {
            for (int k = lo.z(); k <= hi.z(); ++k) {
              const std::size_t cell = index(i, j, k);
              if (pass == 0) {
                ++counts[cell + 1];
              } else {
                cellElements_[static_cast<std::size_t>(cursor_[cell]++)] = e;
              }
            }
          }
        }
      }
      if (pass == 0) {
        for (std::size_t c = 1; c < counts.size(); ++c) {
          counts[c] += counts[c - 1];
        }
        offsets_ = counts;
        cursor_ = counts;
        cellElements_.resize(static_cast<std::size_t>(counts.back()));
      }
    }
  }

  /// The element of center's cell that contains p (largest insideScore, ties to the lower
  /// id), or -1.
  int containingElement(const Eigen::Vector3i& center, const Eigen::Vector3d& p) const {
    int best = -1;
    double bestScore = -std::numeric_limits<double>::infinity();
    for (std::size_t s = offsets_[cellIndex(center)]; s < static_cast<std::size_t>(offsets_[cellIndex(center) + 1]);
         ++s) {
      const int e = cellElements_[s];
      const double score = insideScore(e, p);
      if (score > bestScore || (score == bestScore && e < best)) {
        bestScore = score;
        best = e;
      }
    }
    return best >= 0 && bestScore >= 0.0 ? best : -1;
  }

  /// The element nearest to p (outside every element), by rings of cells around p's cell
  /// until the unexamined cells are provably farther than the best element found.
  int nearestElement(const Eigen::Vector3i& center, const Eigen::Vector3d& p, int stamp, double* dist) {
    int best = -1;
    double bestDistance = std::numeric_limits<double>::infinity();
    for (int ring = 0;; ++ring) {
      for (int i = center.x() - ring; i <= center.x() + ring; ++i) {
        for (int j = center.y() - ring; j <= center.y() + ring; ++j) {
          for (int k = center.z() - ring; k <= center.z() + ring; ++k) {
            const bool onRing =
                std::max({std::abs(i - center.x()), std::abs(j - center.y()), std::abs(k - center.z())}) == ring;
            if (!onRing || i < 0 || j < 0 || k < 0 || i >= cells_[0] || j >= cells_[1] || k >= cells_[2]) {
              continue;
            }
            const std::size_t cell = index(i, j, k);
            for (auto s = static_cast<std::size_t>(offsets_[cell]); s < static_cast<std::size_t>(offsets_[cell + 1]);
                 ++s) {
              const int e = cellElements_[s];
              if (visited_[static_cast<std::size_t>(e)] == stamp) {
                continue;
              }
              visited_[static_cast<std::size_t>(e)] = stamp;
              const double d = distance(e, p);
              if (d < bestDistance || (d == bestDistance && e < best)) {
                bestDistance = d;
                best = e;
              }
            }
          }
        }
      }
      const double bound = unexaminedDistance(center, ring, p);
      if ((best >= 0 && bestDistance <= bound) || bound == std::numeric_limits<double>::infinity()) {
        break;  // nothing closer is left, or every cell was examined
      }
    }
    *dist = bestDistance;
    return best;
  }

  /// A lower bound on the distance from p to elements outside the block of cells within
  /// ring of center: they lie beyond the block along some axis (infinity: no cell is left).
  double unexaminedDistance(const Eigen::Vector3i& center, int ring, const Eigen::Vector3d& p) const {
    double bound = std::numeric_limits<double>::infinity();
    for (int axis = 0; axis < 3; ++axis) {
      if (center[axis] - ring > 0) {
        bound = std::min(bound, std::max(0.0, p[axis] - (lower_[axis] + (center[axis] - ring) * cellSize_)));
      }
      if (center[axis] + ring + 1 < cells_[axis]) {
        bound = std::min(bound, std::max(0.0, (lower_[axis] + (center[axis] + ring + 1) * cellSize_) - p[axis]));
      }
    }
    return bound;
  }

  Eigen::Vector3i cellOf(const Eigen::Vector3d& p) const {
    Eigen::Vector3i cell;
    for (int k = 0; k < 3; ++k) {
      const double t = std::floor((p[k] - lower_[k]) / cellSize_);
      cell[k] = static_cast<int>(std::clamp(t, 0.0, static_cast<double>(cells_[k] - 1)));
    }
    return cell;
  }
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * cells_[1] + static_cast<std::size_t>(j)) * cells_[0] +
           static_cast<std::size_t>(i);
  }
  std::size_t cellIndex(const Eigen::Vector3i& c) const { return index(c.x(), c.y(), c.z()); }

  const TetMesh& mesh_;
  Eigen::Vector3d lower_;
  double cellSize_ = 1.0;
  int cells_[3] = {1, 1, 1};
  std::vector<BoundingBox> boxes_;
  std::vector<Eigen::Matrix3d> inverses_;
  std::vector<int> offsets_;
  std::vector<int> cursor_;
  std::vector<int> cellElements_;
  std::vector<int> visited_;
};

/// Throws ValidationError when a triangle of surface names a vertex it does not have.
void checkTriangles(const SurfaceMesh& surface) {
  const auto m = surface.vertices.cols();
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    for (const int v : surface.triangles[t]) {
      if (v < 0 || v >= m) {
        throw ValidationError("surface triangle " + std::to_string(t) + " names vertex " + std::to_string(v) +
                              ", out of range [0, " + std::to_string(m) + ")");
      }
    }
  }
}

}  // namespace

SurfaceEmbedding SurfaceEmbedding::withWeights(int numTetVertices, SurfaceMesh surface, Eigen::Matrix4Xi tetVertices,
                                               Eigen::Matrix4Xd weights) {
  checkTriangles(surface);
  const auto m = surface.vertices.cols();
  if (tetVertices.cols() != m || weights.cols() != m) {
    throw ValidationError("embedding weights for " + std::to_string(tetVertices.cols()) +
                          " vertices, but the surface has " + std::to_string(m));
  }
  if (m > 0 && (tetVertices.minCoeff() < 0 || tetVertices.maxCoeff() >= numTetVertices)) {
    throw ValidationError("embedding names a tet vertex out of range [0, " + std::to_string(numTetVertices) + ")");
  }
  SurfaceEmbedding embedding;
  embedding.numTetVertices_ = numTetVertices;
  embedding.surface_ = std::move(surface);
  embedding.tetVertices_ = std::move(tetVertices);
  embedding.weights_ = std::move(weights);
  return embedding;
}

SurfaceEmbedding SurfaceEmbedding::boundary(const TetMesh& mesh) {
  SurfaceEmbedding embedding;
  embedding.numTetVertices_ = mesh.numVertices();
  std::vector<int> surfaceIndex(static_cast<std::size_t>(mesh.numVertices()), -1);
  std::vector<int> tetVertex;
  for (std::array<int, 3> triangle : boundaryTriangles(mesh)) {
    for (int& v : triangle) {
      int& id = surfaceIndex[static_cast<std::size_t>(v)];
      if (id < 0) {
        id = static_cast<int>(tetVertex.size());
        tetVertex.push_back(v);
      }
      v = id;
    }
    embedding.surface_.triangles.push_back(triangle);
  }
  const auto m = static_cast<Eigen::Index>(tetVertex.size());
  embedding.surface_.vertices.resize(3, m);
  embedding.tetVertices_.resize(4, m);
  embedding.weights_.resize(4, m);
  for (Eigen::Index k = 0; k < m; ++k) {
    const int v = tetVertex[static_cast<std::size_t>(k)];
    embedding.surface_.vertices.col(k) = mesh.restPosition(v);
    embedding.tetVertices_.col(k).setConstant(v);
    embedding.weights_.col(k) = Eigen::Vector4d(1.0, 0.0, 0.0, 0.0);
  }
  return embedding;
}

SurfaceEmbedding SurfaceEmbedding::embed(const TetMesh& mesh, SurfaceMesh surface) {
  if (mesh.numElements() == 0) {
    throw ValidationError("cannot embed a surface in a volumetric mesh without elements");
  }
  const auto m = surface.vertices.cols();
  checkTriangles(surface);
  SurfaceEmbedding embedding;
  embedding.numTetVertices_ = mesh.numVertices();
  embedding.tetVertices_.resize(mesh.verticesPerElement(), m);
  embedding.weights_.resize(mesh.verticesPerElement(), m);
  ElementGrid grid(mesh);
  for (Eigen::Index k = 0; k < m; ++k) {
    const Eigen::Vector3d p = surface.vertices.col(k);
    double distance = 0.0;
    const int e = grid.locate(p, static_cast<int>(k), &distance);
    embedding.tetVertices_.col(k) = mesh.connectivity().col(e);
    embedding.weights_.col(k) = grid.weights(e, p);
    if (distance > 0.0) {
      ++embedding.numOutside_;
      embedding.maxOutsideDistance_ = std::max(embedding.maxOutsideDistance_, distance);
    }
  }
  embedding.surface_ = std::move(surface);
  return embedding;
}

Eigen::Matrix3Xd SurfaceEmbedding::positions(const Eigen::Ref<const Eigen::VectorXd>& displacement) const {
  if (displacement.size() != 3 * static_cast<Eigen::Index>(numTetVertices_)) {
    throw Error("SurfaceEmbedding: displacement has " + std::to_string(displacement.size()) +
                " entries, expected 3 x " + std::to_string(numTetVertices_));
  }
  Eigen::Matrix3Xd x = surface_.vertices;
  for (Eigen::Index k = 0; k < x.cols(); ++k) {
    Eigen::Vector3d u = weights_(0, k) * displacement.segment<3>(3 * static_cast<Eigen::Index>(tetVertices_(0, k)));
    for (Eigen::Index a = 1; a < tetVertices_.rows(); ++a) {
      u += weights_(a, k) * displacement.segment<3>(3 * static_cast<Eigen::Index>(tetVertices_(a, k)));
    }
    x.col(k) += u;
  }
  return x;
}

Eigen::Matrix3Xf SurfaceEmbedding::interpolate(const Eigen::Matrix3Xf& perTetVertex) const {
  if (perTetVertex.cols() != numTetVertices_) {
    throw Error("SurfaceEmbedding: attribute has " + std::to_string(perTetVertex.cols()) + " columns, expected " +
                std::to_string(numTetVertices_));
  }
  Eigen::Matrix3Xf out(3, surface_.vertices.cols());
  for (Eigen::Index k = 0; k < out.cols(); ++k) {
    Eigen::Vector3f value = Eigen::Vector3f::Zero();
    for (Eigen::Index a = 0; a < tetVertices_.rows(); ++a) {
      value += static_cast<float>(weights_(a, k)) * perTetVertex.col(tetVertices_(a, k));
    }
    out.col(k) = value.cwiseMax(0.0F).cwiseMin(1.0F);
  }
  return out;
}

}  // namespace asyncfem
