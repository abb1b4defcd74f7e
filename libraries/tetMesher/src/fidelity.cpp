// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/elementSets.hpp>
#include <asyncfem/tetMesher/fidelity.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <sstream>
#include <vector>

namespace asyncfem {

namespace {

/// Corners, edge midpoints and centroid of every triangle, with the triangle's index.
template <class Visit>
void forEachSample(const TriangleSurface& surface, Visit visit) {
  for (int t = 0; t < surface.numTriangles(); ++t) {
    const Eigen::Vector3d a = surface.vertices.col(surface.triangles(0, t));
    const Eigen::Vector3d b = surface.vertices.col(surface.triangles(1, t));
    const Eigen::Vector3d c = surface.vertices.col(surface.triangles(2, t));
    for (const Eigen::Vector3d& x : {a, b, c, Eigen::Vector3d(0.5 * (a + b)), Eigen::Vector3d(0.5 * (b + c)),
                                     Eigen::Vector3d(0.5 * (c + a)), Eigen::Vector3d((a + b + c) / 3.0)})
      visit(x, t);
  }
}

std::string point(const Eigen::Vector3d& x) {
  std::ostringstream out;
  out.precision(6);
  out << "(" << x.x() << ", " << x.y() << ", " << x.z() << ")";
  return out.str();
}

}  // namespace

TriangleSurface boundaryTriangleSurface(const TetMesh& mesh) {
  const auto triangles = boundaryTriangles(mesh);
  TriangleSurface surface;
  surface.vertices = mesh.restPositions();
  surface.triangles.resize(3, static_cast<Eigen::Index>(triangles.size()));
  for (std::size_t t = 0; t < triangles.size(); ++t)
    surface.triangles.col(static_cast<Eigen::Index>(t)) =
        Eigen::Vector3i(triangles[t][0], triangles[t][1], triangles[t][2]);
  surface.triangleParts.assign(triangles.size(), 0);
  surface.partNames = {"boundary"};
  return surface;
}

SurfaceDeviation surfaceDeviation(const TetMesh& mesh, const SignedDistance& distance) {
  SurfaceDeviation deviation;
  const TriangleSurface boundary = boundaryTriangleSurface(mesh);
  if (boundary.numTriangles() == 0) throw ValidationError("surfaceDeviation: the mesh has no boundary");
  forEachSample(boundary, [&](const Eigen::Vector3d& x, int) {
    const double d = distance.distance(x);
    if (d > deviation.meshToSurface) {
      deviation.meshToSurface = d;
      deviation.meshToSurfaceAt = x;
    }
  });
  const SignedDistance toBoundary(boundary);
  forEachSample(distance.surface(), [&](const Eigen::Vector3d& x, int t) {
    const double d = toBoundary.distance(x);
    if (d > deviation.surfaceToMesh) {
      deviation.surfaceToMesh = d;
      deviation.surfaceToMeshAt = x;
      deviation.surfaceToMeshTriangle = t;
    }
  });
  return deviation;
}

double implicitDeviation(const TetMesh& mesh, const ImplicitFunction& f, Eigen::Vector3d* where) {
  double worst = 0.0;
  forEachSample(boundaryTriangleSurface(mesh), [&](const Eigen::Vector3d& x, int) {
    const double d = std::abs(f(x));
    if (d > worst) {
      worst = d;
      if (where != nullptr) *where = x;
    }
  });
  return worst;
}

double requireRepairableHoles(const TetMesh& mesh, const SignedDistance& distance, double spacing, double maxFraction,
                              const std::string& source) {
  const TriangleSurface boundary = boundaryTriangleSurface(mesh);
  double total = 0.0, invented = 0.0, farthest = 0.0;
  Eigen::Vector3d farthestAt = Eigen::Vector3d::Zero();
  for (int t = 0; t < boundary.numTriangles(); ++t) {
    const Eigen::Vector3d a = boundary.vertices.col(boundary.triangles(0, t));
    const Eigen::Vector3d b = boundary.vertices.col(boundary.triangles(1, t));
    const Eigen::Vector3d c = boundary.vertices.col(boundary.triangles(2, t));
    const double area = 0.5 * (b - a).cross(c - a).norm();
    const Eigen::Vector3d centroid = (a + b + c) / 3.0;
    const double d = distance.distance(centroid);
    total += area;
    if (d > spacing) invented += area;
    if (d > farthest) {
      farthest = d;
      farthestAt = centroid;
    }
  }
  const double fraction = total > 0.0 ? invented / total : 0.0;
  if (!(fraction > maxFraction)) return fraction;
  int triangle = -1;
  distance.distance(farthestAt, &triangle);
  std::ostringstream out;
  out.precision(4);
  out << source << ": open beyond repair: " << 100.0 * fraction
      << "% of the mesh boundary is more than a spacing from every input triangle (limit " << 100.0 * maxFraction
      << "%): the winding number spans large openings, the widest near " << point(farthestAt) << ", " << farthest
      << " from the nearest input triangle, #" << inputTriangleIndex(distance.surface(), triangle)
      << "; close the surface around that place";
  throw ValidationError(out.str());
}

void requireNoSelfOverlap(const TetMesh& mesh, const SignedDistance& distance, const std::string& source,
                          int maxSamples) {
  const int n = mesh.numElements();
  if (n == 0) return;
  const int stride = std::max(1, n / std::max(1, maxSamples));
  const Eigen::Matrix3Xd centroids = elementCentroids(mesh);
  for (int e = 0; e < n; e += stride) {
    const Eigen::Vector3d x = centroids.col(e);
    const double w = distance.windingNumber(x);
    if (w > 1.5 || w < -0.5) {
      int triangle = -1;
      distance.distance(x, &triangle);
      std::ostringstream out;
      out.precision(4);
      out << source << ": the surface intersects or overlaps itself: the point " << point(x)
          << " is enclosed with winding number " << w << " (nearest triangle #"
          << inputTriangleIndex(distance.surface(), triangle)
          << "); remove the overlap, or mesh the union of the shells with --repair (generalized winding number)";
      throw ValidationError(out.str());
    }
  }
}

}  // namespace asyncfem
