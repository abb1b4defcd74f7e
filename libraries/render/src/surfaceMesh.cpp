// SPDX-License-Identifier: BSD-3-Clause
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <assimp/Importer.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/surfaceMesh.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace asyncfem {

namespace {

/// Welds vertices at exactly the same position, across seams and across a file's meshes.
class VertexWelder {
 public:
  /// The welded ids of mesh's vertices, adding the positions not seen before.
  std::vector<int> weld(const aiMesh& mesh) {
    std::vector<int> ids(mesh.mNumVertices);
    for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
      const aiVector3D& p = mesh.mVertices[v];
      const std::array<double, 3> key{p.x, p.y, p.z};
      const auto [it, inserted] = vertexIds_.emplace(key, static_cast<int>(vertices_.size()));
      if (inserted) {
        vertices_.emplace_back(key[0], key[1], key[2]);
      }
      ids[v] = it->second;
    }
    return ids;
  }
  /// Every welded vertex, 3 x m.
  Eigen::Matrix3Xd vertices() const {
    Eigen::Matrix3Xd positions(3, static_cast<Eigen::Index>(vertices_.size()));
    for (std::size_t v = 0; v < vertices_.size(); ++v) {
      positions.col(static_cast<Eigen::Index>(v)) = vertices_[v];
    }
    return positions;
  }

 private:
  std::vector<Eigen::Vector3d> vertices_;
  std::map<std::array<double, 3>, int> vertexIds_;
};

/// Appends mesh's triangles in welded vertex ids, skipping points, lines and triangles
/// the welding collapsed.
void appendTriangles(const aiMesh& mesh, const std::vector<int>& ids, std::vector<std::array<int, 3>>& triangles) {
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) {
      continue;
    }
    const std::array<int, 3> triangle{ids[face.mIndices[0]], ids[face.mIndices[1]], ids[face.mIndices[2]]};
    if (triangle[0] == triangle[1] || triangle[1] == triangle[2] || triangle[0] == triangle[2]) {
      continue;
    }
    triangles.push_back(triangle);
  }
}

}  // namespace

SurfaceMesh loadSurfaceMesh(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) {
    throw Error(path.string() + ": no such file");
  }
  Assimp::Importer importer;
  // Pre-transforming bakes the node hierarchy into the vertex positions; meshes whose
  // primitives are points or lines keep them as such and are skipped below.
  const aiScene* scene = importer.ReadFile(
      path.string(), aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_JoinIdenticalVertices);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    throw Error(path.string() + ": cannot read surface mesh: " + importer.GetErrorString());
  }
  SurfaceMesh surface;
  VertexWelder welder;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& mesh = *scene->mMeshes[m];
    appendTriangles(mesh, welder.weld(mesh), surface.triangles);
  }
  if (surface.triangles.empty()) {
    throw Error(path.string() + ": the surface mesh holds no triangle");
  }
  surface.vertices = welder.vertices();
  return surface;
}

void writeObj(const std::filesystem::path& path, const SurfaceMesh& surface) {
  std::ofstream out(path);
  if (!out) {
    throw Error(path.string() + ": cannot create file");
  }
  char line[128];
  for (Eigen::Index v = 0; v < surface.vertices.cols(); ++v) {
    std::snprintf(line, sizeof(line), "v %.17g %.17g %.17g\n", surface.vertices(0, v), surface.vertices(1, v),
                  surface.vertices(2, v));
    out << line;
  }
  for (const auto& t : surface.triangles) {
    out << "f " << (t[0] + 1) << ' ' << (t[1] + 1) << ' ' << (t[2] + 1) << '\n';
  }
  if (!out) {
    throw Error(path.string() + ": write failed");
  }
}

SurfaceMesh sphereSurface(const Eigen::Vector3d& center, double radius, int refinements) {
  if (!(radius > 0.0) || !std::isfinite(radius)) {
    throw Error("sphereSurface: the radius must be positive and finite, got " + std::to_string(radius));
  }
  if (refinements < 0 || refinements > 6) {
    throw Error("sphereSurface: refinements must be in [0, 6], got " + std::to_string(refinements));
  }
  // The icosahedron's 12 vertices are the cyclic permutations of (0, +-1, +-t), t the
  // golden ratio; its 20 faces, counter-clockwise from outside.
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> points = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (Eigen::Vector3d& p : points) p.normalize();
  std::vector<std::array<int, 3>> faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                           {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                           {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                           {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < refinements; ++level) {
    std::map<std::pair<int, int>, int> midpoints;  // each edge split once, shared by its two faces
    const auto midpoint = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      const auto [it, inserted] = midpoints.emplace(key, static_cast<int>(points.size()));
      if (inserted) points.push_back((points[a] + points[b]).normalized());
      return it->second;
    };
    std::vector<std::array<int, 3>> finer;
    finer.reserve(faces.size() * 4);
    for (const auto& [a, b, c] : faces) {
      const int ab = midpoint(a, b);
      const int bc = midpoint(b, c);
      const int ca = midpoint(c, a);
      finer.push_back({a, ab, ca});
      finer.push_back({b, bc, ab});
      finer.push_back({c, ca, bc});
      finer.push_back({ab, bc, ca});
    }
    faces = std::move(finer);
  }
  SurfaceMesh sphere;
  sphere.vertices.resize(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t v = 0; v < points.size(); ++v) {
    sphere.vertices.col(static_cast<Eigen::Index>(v)) = center + (radius * points[v]);
  }
  sphere.triangles = std::move(faces);
  return sphere;
}

}  // namespace asyncfem
