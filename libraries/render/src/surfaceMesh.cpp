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

namespace asyncfem {

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
  std::vector<Eigen::Vector3d> vertices;
  // Exact-position welding across seams and across the file's meshes.
  std::map<std::array<double, 3>, int> vertexIds;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    std::vector<int> ids(mesh->mNumVertices);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      const std::array<double, 3> key{p.x, p.y, p.z};
      const auto [it, inserted] = vertexIds.emplace(key, static_cast<int>(vertices.size()));
      if (inserted) {
        vertices.emplace_back(key[0], key[1], key[2]);
      }
      ids[v] = it->second;
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) {
        continue;
      }
      const std::array<int, 3> triangle{ids[face.mIndices[0]], ids[face.mIndices[1]], ids[face.mIndices[2]]};
      if (triangle[0] == triangle[1] || triangle[1] == triangle[2] || triangle[0] == triangle[2]) {
        continue;  // collapsed by the welding
      }
      surface.triangles.push_back(triangle);
    }
  }
  if (surface.triangles.empty()) {
    throw Error(path.string() + ": the surface mesh holds no triangle");
  }
  surface.vertices.resize(3, static_cast<Eigen::Index>(vertices.size()));
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    surface.vertices.col(static_cast<Eigen::Index>(v)) = vertices[v];
  }
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
