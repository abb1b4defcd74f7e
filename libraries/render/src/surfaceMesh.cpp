// SPDX-License-Identifier: BSD-3-Clause
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <array>
#include <assimp/Importer.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/surfaceMesh.hpp>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <string>
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

}  // namespace asyncfem
