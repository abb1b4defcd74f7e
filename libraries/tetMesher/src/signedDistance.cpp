// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/signedDistance.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <utility>

namespace asyncfem {

namespace {

/// Which feature of a triangle holds the closest point: the face, edge i (corners i and
/// i+1), or corner i.
enum class Feature { Face, Edge, Vertex };

struct ClosestPoint {
  Eigen::Vector3d point;
  Feature feature = Feature::Face;
  int index = 0;  // edge or corner index
};

/// Closest point of triangle (a, b, c) to p, by the Voronoi region of p among the
/// triangle's corners, edges and face (tested in that order through dot products of the
/// edge vectors with p's offsets).
ClosestPoint closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                    const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, Feature::Vertex, 0};
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, Feature::Vertex, 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return {a + (d1 / (d1 - d3)) * ab, Feature::Edge, 0};
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, Feature::Vertex, 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return {a + (d2 / (d2 - d6)) * ac, Feature::Edge, 2};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    return {b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), Feature::Edge, 1};
  }
  const double scale = 1.0 / (va + vb + vc);
  return {a + ab * (vb * scale) + ac * (vc * scale), Feature::Face, 0};
}

struct Node {
  Eigen::AlignedBox3d box;
  int left = -1, right = -1;                             // children, or -1 for a leaf
  int begin = 0, end = 0;                                // leaf: triangles order[begin, end)
  Eigen::Vector3d areaNormal = Eigen::Vector3d::Zero();  // sum of area-weighted normals
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();      // area-weighted centroid
  double radius = 0.0;                                   // max distance from centre to a vertex
};

}  // namespace

struct SignedDistance::Impl {
  TriangleSurface surface;
  SignMode mode = SignMode::Pseudonormal;
  double farFieldRatio = 2.0;
  std::vector<Node> nodes;
  std::vector<int> order;
  std::vector<Eigen::Vector3d> faceNormals;                 // unit
  std::vector<std::array<Eigen::Vector3d, 3>> edgeNormals;  // per triangle, edge i = (i, i+1)
  std::vector<Eigen::Vector3d> vertexNormals;               // angle-weighted

  Eigen::Vector3d corner(int t, int c) const { return surface.vertices.col(surface.triangles(c, t)); }

  int build(int begin, int end, const std::vector<Eigen::Vector3d>& centroids) {
    Node node;
    node.begin = begin;
    node.end = end;
    Eigen::AlignedBox3d centroidBox;
    double area = 0.0;
    for (int i = begin; i < end; ++i) {
      const int t = order[static_cast<std::size_t>(i)];
      for (int c = 0; c < 3; ++c) node.box.extend(corner(t, c));
      centroidBox.extend(centroids[static_cast<std::size_t>(t)]);
      const Eigen::Vector3d n = 0.5 * (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0));
      node.areaNormal += n;
      area += n.norm();
      node.centre += n.norm() * centroids[static_cast<std::size_t>(t)];
    }
    node.centre = area > 0.0 ? Eigen::Vector3d(node.centre / area) : node.box.center();
    for (int i = begin; i < end; ++i)
      for (int c = 0; c < 3; ++c)
        node.radius = std::max(node.radius, (corner(order[static_cast<std::size_t>(i)], c) - node.centre).norm());
    const int index = static_cast<int>(nodes.size());
    nodes.push_back(node);
    if (end - begin > 4) {
      int axis = 0;
      centroidBox.sizes().maxCoeff(&axis);
      const int middle = begin + (end - begin) / 2;
      std::nth_element(order.begin() + begin, order.begin() + middle, order.begin() + end, [&](int x, int y) {
        return centroids[static_cast<std::size_t>(x)][axis] < centroids[static_cast<std::size_t>(y)][axis];
      });
      const int left = build(begin, middle, centroids);
      const int right = build(middle, end, centroids);
      nodes[static_cast<std::size_t>(index)].left = left;
      nodes[static_cast<std::size_t>(index)].right = right;
    }
    return index;
  }

  void computeNormals() {
    const int m = surface.numTriangles();
    faceNormals.resize(static_cast<std::size_t>(m));
    vertexNormals.assign(static_cast<std::size_t>(surface.numVertices()), Eigen::Vector3d::Zero());
    std::map<std::pair<int, int>, Eigen::Vector3d> edgeSums;
    for (int t = 0; t < m; ++t) {
      const Eigen::Vector3d n = (corner(t, 1) - corner(t, 0)).cross(corner(t, 2) - corner(t, 0));
      const double length = n.norm();
      faceNormals[static_cast<std::size_t>(t)] = length > 0.0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d::Zero();
      for (int c = 0; c < 3; ++c) {
        const int u = surface.triangles(c, t), v = surface.triangles((c + 1) % 3, t);
        auto [it, inserted] = edgeSums.try_emplace({std::min(u, v), std::max(u, v)}, Eigen::Vector3d::Zero());
        it->second += faceNormals[static_cast<std::size_t>(t)];
        const Eigen::Vector3d e1 = corner(t, (c + 1) % 3) - corner(t, c);
        const Eigen::Vector3d e2 = corner(t, (c + 2) % 3) - corner(t, c);
        const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
        vertexNormals[static_cast<std::size_t>(u)] += angle * faceNormals[static_cast<std::size_t>(t)];
      }
    }
    edgeNormals.resize(static_cast<std::size_t>(m));
    for (int t = 0; t < m; ++t)
      for (int c = 0; c < 3; ++c) {
        const int u = surface.triangles(c, t), v = surface.triangles((c + 1) % 3, t);
        edgeNormals[static_cast<std::size_t>(t)][static_cast<std::size_t>(c)] =
            edgeSums.at({std::min(u, v), std::max(u, v)});
      }
  }

  /// Nearest triangle: squared distance, triangle, closest point.
  std::pair<int, ClosestPoint> nearest(const Eigen::Vector3d& x, double& bestSquared) const {
    bestSquared = std::numeric_limits<double>::infinity();
    int best = -1;
    ClosestPoint bestPoint{x, Feature::Face, 0};
    std::array<int, 128> stack{};
    int top = 0;
    stack[static_cast<std::size_t>(top++)] = 0;
    while (top > 0) {
      const Node& node = nodes[static_cast<std::size_t>(stack[static_cast<std::size_t>(--top)])];
      if (node.box.squaredExteriorDistance(x) >= bestSquared) continue;
      if (node.left < 0) {
        for (int i = node.begin; i < node.end; ++i) {
          const int t = order[static_cast<std::size_t>(i)];
          const ClosestPoint cp = closestPointOnTriangle(x, corner(t, 0), corner(t, 1), corner(t, 2));
          const double d = (cp.point - x).squaredNorm();
          if (d < bestSquared) {
            bestSquared = d;
            best = t;
            bestPoint = cp;
          }
        }
        continue;
      }
      const Node& left = nodes[static_cast<std::size_t>(node.left)];
      const Node& right = nodes[static_cast<std::size_t>(node.right)];
      // Visit the nearer child first (pushed last).
      const bool leftFirst = left.box.squaredExteriorDistance(x) <= right.box.squaredExteriorDistance(x);
      stack[static_cast<std::size_t>(top++)] = leftFirst ? node.right : node.left;
      stack[static_cast<std::size_t>(top++)] = leftFirst ? node.left : node.right;
    }
    return {best, bestPoint};
  }

  double winding(const Eigen::Vector3d& x) const {
    double total = 0.0;
    std::array<int, 128> stack{};
    int top = 0;
    stack[static_cast<std::size_t>(top++)] = 0;
    while (top > 0) {
      const Node& node = nodes[static_cast<std::size_t>(stack[static_cast<std::size_t>(--top)])];
      const Eigen::Vector3d offset = node.centre - x;
      const double distance = offset.norm();
      if (distance > farFieldRatio * node.radius && node.end - node.begin > 1) {
        // Far field: the cluster acts as one dipole of moment areaNormal at its centre.
        total += offset.dot(node.areaNormal) / (distance * distance * distance);
        continue;
      }
      if (node.left >= 0) {
        stack[static_cast<std::size_t>(top++)] = node.left;
        stack[static_cast<std::size_t>(top++)] = node.right;
        continue;
      }
      for (int i = node.begin; i < node.end; ++i) {
        const int t = order[static_cast<std::size_t>(i)];
        const Eigen::Vector3d a = corner(t, 0) - x, b = corner(t, 1) - x, c = corner(t, 2) - x;
        const double la = a.norm(), lb = b.norm(), lc = c.norm();
        // Solid angle of the triangle seen from x (Van Oosterom & Strackee 1983).
        const double numerator = a.dot(b.cross(c));
        const double denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        total += 2.0 * std::atan2(numerator, denominator);
      }
    }
    return total / (4.0 * std::numbers::pi);
  }

  double signedDistance(const Eigen::Vector3d& x) const {
    double squared = 0.0;
    const auto [t, closest] = nearest(x, squared);
    const double distance = std::sqrt(squared);
    if (mode == SignMode::WindingNumber) return winding(x) > 0.5 ? -distance : distance;
    if (distance == 0.0) return 0.0;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    switch (closest.feature) {
      case Feature::Face:
        normal = faceNormals[static_cast<std::size_t>(t)];
        break;
      case Feature::Edge:
        normal = edgeNormals[static_cast<std::size_t>(t)][static_cast<std::size_t>(closest.index)];
        break;
      case Feature::Vertex:
        normal = vertexNormals[static_cast<std::size_t>(surface.triangles(closest.index, t))];
        break;
    }
    return (x - closest.point).dot(normal) < 0.0 ? -distance : distance;
  }
};

SignedDistance::SignedDistance(TriangleSurface surface, SignMode mode, double farFieldRatio)
    : impl_(std::make_unique<Impl>()) {
  if (surface.numTriangles() == 0) throw ValidationError("SignedDistance: the surface has no triangles");
  if (!(farFieldRatio > 1.0)) throw ValidationError("SignedDistance: farFieldRatio must be > 1");
  impl_->surface = std::move(surface);
  impl_->mode = mode;
  impl_->farFieldRatio = farFieldRatio;
  const int m = impl_->surface.numTriangles();
  for (int t = 0; t < m; ++t)
    for (int c = 0; c < 3; ++c) {
      const int v = impl_->surface.triangles(c, t);
      if (v < 0 || v >= impl_->surface.numVertices()) {
        throw ValidationError("SignedDistance: triangle " + std::to_string(t) + " has vertex " + std::to_string(v) +
                              " out of range");
      }
    }
  std::vector<Eigen::Vector3d> centroids(static_cast<std::size_t>(m));
  for (int t = 0; t < m; ++t)
    centroids[static_cast<std::size_t>(t)] = (impl_->corner(t, 0) + impl_->corner(t, 1) + impl_->corner(t, 2)) / 3.0;
  impl_->order.resize(static_cast<std::size_t>(m));
  std::iota(impl_->order.begin(), impl_->order.end(), 0);
  impl_->build(0, m, centroids);
  impl_->computeNormals();
}

SignedDistance::~SignedDistance() = default;
SignedDistance::SignedDistance(SignedDistance&&) noexcept = default;
SignedDistance& SignedDistance::operator=(SignedDistance&&) noexcept = default;

double SignedDistance::distance(const Eigen::Vector3d& x, int* nearestTriangle) const {
  double squared = 0.0;
  const auto [triangle, point] = impl_->nearest(x, squared);
  if (nearestTriangle != nullptr) *nearestTriangle = triangle;
  return std::sqrt(squared);
}

double SignedDistance::windingNumber(const Eigen::Vector3d& x) const { return impl_->winding(x); }

double SignedDistance::operator()(const Eigen::Vector3d& x) const { return impl_->signedDistance(x); }

const TriangleSurface& SignedDistance::surface() const { return impl_->surface; }
SignMode SignedDistance::mode() const { return impl_->mode; }

ImplicitFunction SignedDistance::function() const {
  const Impl* impl = impl_.get();
  return [impl](const Eigen::Vector3d& x) { return impl->signedDistance(x); };
}

}  // namespace asyncfem
