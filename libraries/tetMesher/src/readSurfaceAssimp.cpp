// SPDX-License-Identifier: BSD-3-Clause
// readSurface through assimp; compiled only with ASYNCFEM_WITH_ASSIMP=ON (otherwise
// readSurfaceUnavailable.cpp provides the functions).
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/triangleSurface.hpp>
#include <map>
#include <string>
#include <vector>

namespace asyncfem {

namespace {

Eigen::Matrix4d toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return out;
}

struct Collector {
  const aiScene* scene = nullptr;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
  std::vector<int> parts, materials, groups;
  /// Names and their indices, for parts, materials and groups.
  struct Names {
    std::vector<std::string> names;
    std::map<std::string, int> index;
    int operator()(const std::string& name) {
      const auto [it, inserted] = index.try_emplace(name, static_cast<int>(names.size()));
      if (inserted) names.push_back(name);
      return it->second;
    }
  };
  Names partNames, materialNames, groupNames;

  void visit(const aiNode* node, const Eigen::Matrix4d& parentTransform, const std::string& parentGroup) {
    const Eigen::Matrix4d transform = parentTransform * toEigen(node->mTransformation);
    // The group is the node's own name (OBJ g/o, glTF and FBX nodes); unnamed nodes belong
    // to their parent's group.
    const bool named = node != scene->mRootNode && node->mName.length > 0;
    const std::string group = named ? std::string(node->mName.C_Str()) : parentGroup;
    for (unsigned i = 0; i < node->mNumMeshes; ++i) {
      const aiMesh* mesh = scene->mMeshes[node->mMeshes[i]];
      std::string name = mesh->mName.length > 0 ? std::string(mesh->mName.C_Str()) : std::string(node->mName.C_Str());
      if (name.empty()) name = "part" + std::to_string(node->mMeshes[i]);
      const int partId = partNames(name);
      aiString materialName;
      std::string material = "material" + std::to_string(mesh->mMaterialIndex);
      if (mesh->mMaterialIndex < scene->mNumMaterials &&
          scene->mMaterials[mesh->mMaterialIndex]->Get(AI_MATKEY_NAME, materialName) == AI_SUCCESS &&
          materialName.length > 0)
        material = materialName.C_Str();
      const int materialId = materialNames(material);
      const int groupId = groupNames(group.empty() ? "group" : group);
      const int offset = static_cast<int>(vertices.size());
      for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
        const aiVector3D& p = mesh->mVertices[v];
        const Eigen::Vector4d x = transform * Eigen::Vector4d(p.x, p.y, p.z, 1.0);
        vertices.emplace_back(x.head<3>() / x[3]);
      }
      for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
        const aiFace& face = mesh->mFaces[f];
        if (face.mNumIndices != 3) continue;  // points and lines
        triangles.emplace_back(offset + static_cast<int>(face.mIndices[0]), offset + static_cast<int>(face.mIndices[1]),
                               offset + static_cast<int>(face.mIndices[2]));
        parts.push_back(partId);
        materials.push_back(materialId);
        groups.push_back(groupId);
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) visit(node->mChildren[c], transform, group);
  }
};

}  // namespace

bool surfaceReaderAvailable() { return true; }

TriangleSurface readSurface(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw Error(path.string() + ": no such file");
  Assimp::Importer importer;
  // Triangulate polygons; keep vertices as stored (welding is the caller's step) and
  // do not let assimp drop or reorder anything else.
  const aiScene* scene = importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_SortByPType);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    throw Error(path.string() + ": cannot read the surface: " + importer.GetErrorString());
  }
  Collector collector;
  collector.scene = scene;
  // The root node carries the file's name, not a group: its own meshes form group "root".
  collector.visit(scene->mRootNode, Eigen::Matrix4d::Identity(), "root");
  if (collector.triangles.empty()) throw ValidationError(path.string() + ": the file holds no triangles");
  TriangleSurface surface;
  surface.vertices.resize(3, static_cast<Eigen::Index>(collector.vertices.size()));
  for (std::size_t v = 0; v < collector.vertices.size(); ++v)
    surface.vertices.col(static_cast<Eigen::Index>(v)) = collector.vertices[v];
  surface.triangles.resize(3, static_cast<Eigen::Index>(collector.triangles.size()));
  for (std::size_t t = 0; t < collector.triangles.size(); ++t)
    surface.triangles.col(static_cast<Eigen::Index>(t)) = collector.triangles[t];
  surface.triangleParts = std::move(collector.parts);
  surface.partNames = std::move(collector.partNames.names);
  surface.triangleMaterials = std::move(collector.materials);
  surface.materialNames = std::move(collector.materialNames.names);
  surface.triangleGroups = std::move(collector.groups);
  surface.groupNames = std::move(collector.groupNames.names);
  return surface;
}

}  // namespace asyncfem
