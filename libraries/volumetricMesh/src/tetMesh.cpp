// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <cmath>
#include <string>

namespace asyncfem {

namespace {

void checkMaterial(const Material& m) {
  const bool finite = std::isfinite(m.density) && std::isfinite(m.youngsModulus) && std::isfinite(m.poissonRatio);
  if (!finite || m.density <= 0.0 || m.youngsModulus <= 0.0 || m.poissonRatio <= -1.0 || m.poissonRatio >= 0.5) {
    throw ValidationError("material '" + m.name + "': need density > 0, E > 0 and -1 < nu < 0.5 (got density " +
                          std::to_string(m.density) + ", E " + std::to_string(m.youngsModulus) + ", nu " +
                          std::to_string(m.poissonRatio) + ")");
  }
}

std::vector<int> sortedUnique(std::vector<int> ids) {
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

}  // namespace

const char* elementKindPlural(ElementKind kind) { return kind == ElementKind::hexahedron ? "hexahedra" : "tetrahedra"; }

TetMesh::TetMesh(Eigen::Matrix3Xd restPositions, Eigen::Matrix4Xi elements, std::vector<Material> materials,
                 std::vector<int> elementMaterials)
    : restPositions_(std::move(restPositions)),
      elements_(std::move(elements)),
      materials_(std::move(materials)),
      elementMaterials_(std::move(elementMaterials)) {
  validate();
}

TetMesh::TetMesh(Eigen::Matrix3Xd restPositions, HexElements hexahedra, std::vector<Material> materials,
                 std::vector<int> elementMaterials)
    : kind_(ElementKind::hexahedron),
      restPositions_(std::move(restPositions)),
      hexahedra_(std::move(hexahedra)),
      materials_(std::move(materials)),
      elementMaterials_(std::move(elementMaterials)) {
  validate();
}

void TetMesh::throwTetrahedraOnly(std::string_view what) const {
  throw ValidationError(std::string(what) + " supports tetrahedral meshes only; this mesh has " +
                        std::to_string(numElements()) + " " + elementKindPlural(kind_) +
                        " (convert them into tetrahedra, 6 per hexahedron: meshInfo MESH --hex-to-tets "
                        "--write OUT.veg)");
}

const HexElements& TetMesh::hexahedra() const {
  if (kind_ != ElementKind::hexahedron) {
    throw ValidationError("hexahedra() asked of a mesh of " + std::to_string(numElements()) + " tetrahedra");
  }
  return hexahedra_;
}

Eigen::Matrix<double, 3, 8> TetMesh::hexahedronRestPositions(int e) const {
  const HexElements& hexahedra = this->hexahedra();
  Eigen::Matrix<double, 3, 8> x;
  for (int a = 0; a < 8; ++a) x.col(a) = restPositions_.col(hexahedra(a, e));
  return x;
}

void TetMesh::validate() const {
  for (int v = 0; v < numVertices(); ++v) {
    if (!restPositions_.col(v).allFinite()) {
      throw ValidationError("vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  if (elementMaterials_.size() != static_cast<std::size_t>(numElements())) {
    throw ValidationError("mesh has " + std::to_string(numElements()) + " elements but " +
                          std::to_string(elementMaterials_.size()) + " element material entries");
  }
  for (const Material& m : materials_) checkMaterial(m);
  const auto elements = connectivity();
  const int corners = verticesPerElement();
  for (int e = 0; e < numElements(); ++e) {
    const auto t = elements.col(e);
    for (int a = 0; a < corners; ++a) {
      if (t[a] < 0 || t[a] >= numVertices()) {
        throw ValidationError("element " + std::to_string(e) + " references vertex " + std::to_string(t[a]) +
                              ", outside [0, " + std::to_string(numVertices()) + ")");
      }
      for (int b = 0; b < a; ++b) {
        if (t[a] == t[b]) {
          throw ValidationError("element " + std::to_string(e) + " uses vertex " + std::to_string(t[a]) + " twice");
        }
      }
    }
    const int mat = elementMaterials_[static_cast<std::size_t>(e)];
    if (mat < 0 || static_cast<std::size_t>(mat) >= materials_.size()) {
      throw ValidationError("element " + std::to_string(e) + " has material index " + std::to_string(mat) +
                            " but the mesh has " + std::to_string(materials_.size()) + " materials");
    }
  }
}

Eigen::Matrix<double, 3, 4> TetMesh::elementRestPositions(int e) const {
  const Eigen::Matrix4Xi& elements = this->elements();
  Eigen::Matrix<double, 3, 4> x;
  for (int a = 0; a < 4; ++a) x.col(a) = restPositions_.col(elements(a, e));
  return x;
}

int TetMesh::findMaterial(const std::string& name) const {
  for (std::size_t i = 0; i < materials_.size(); ++i) {
    if (materials_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

int TetMesh::addMaterial(const Material& material) {
  checkMaterial(material);
  const int existing = findMaterial(material.name);
  if (existing >= 0) {
    materials_[static_cast<std::size_t>(existing)] = material;
    return existing;
  }
  materials_.push_back(material);
  return static_cast<int>(materials_.size()) - 1;
}

void TetMesh::assignMaterial(const std::string& setName, int materialIndex) {
  if (materialIndex < 0 || static_cast<std::size_t>(materialIndex) >= materials_.size()) {
    throw ValidationError("material index " + std::to_string(materialIndex) + " out of range");
  }
  for (int e : elementSet(setName)) elementMaterials_[static_cast<std::size_t>(e)] = materialIndex;
}

std::vector<int> TetMesh::elementSet(const std::string& name) const {
  if (auto it = elementSets_.find(name); it != elementSets_.end()) return it->second;
  if (name == "allElements") {
    std::vector<int> all(static_cast<std::size_t>(numElements()));
    for (int e = 0; e < numElements(); ++e) all[static_cast<std::size_t>(e)] = e;
    return all;
  }
  std::string known;
  for (const auto& [n, s] : elementSets_) known += (known.empty() ? "" : ", ") + n;
  throw ValidationError("unknown element set '" + name + "' (known: allElements" + (known.empty() ? "" : ", ") + known +
                        ")");
}

const std::vector<int>& TetMesh::vertexSet(const std::string& name) const {
  if (auto it = vertexSets_.find(name); it != vertexSets_.end()) return it->second;
  std::string known;
  for (const auto& [n, s] : vertexSets_) known += (known.empty() ? "" : ", ") + n;
  throw ValidationError("unknown vertex set '" + name + "' (known: " + (known.empty() ? "none" : known) + ")");
}

std::vector<int> TetMesh::setVertices(const std::string& name) const {
  if (auto it = vertexSets_.find(name); it != vertexSets_.end()) return it->second;
  if (auto it = elementSets_.find(name); it != elementSets_.end()) {
    std::vector<int> vertices;
    const int corners = verticesPerElement();
    vertices.reserve(it->second.size() * static_cast<std::size_t>(corners));
    for (int e : it->second)
      for (int a = 0; a < corners; ++a) vertices.push_back(elementVertex(e, a));
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    return vertices;
  }
  const auto list = [](const std::map<std::string, std::vector<int>>& sets) {
    std::string known;
    for (const auto& [n, s] : sets) known += (known.empty() ? "" : ", ") + n;
    return known.empty() ? std::string("none") : known;
  };
  throw ValidationError("unknown set '" + name + "' (vertex sets: " + list(vertexSets_) +
                        "; element sets: " + list(elementSets_) + ")");
}

void TetMesh::renameSet(const std::string& from, const std::string& to) {
  if (to.empty()) throw ValidationError("renaming set '" + from + "': the new name is empty");
  const bool element = elementSets_.count(from) > 0;
  const bool vertex = vertexSets_.count(from) > 0;
  if (!element && !vertex) (void)setVertices(from);  // throws, naming the known sets
  if (from == to) return;
  for (auto* sets : {element ? &elementSets_ : nullptr, vertex ? &vertexSets_ : nullptr}) {
    if (sets != nullptr && sets->count(to) > 0) {
      throw ValidationError("renaming set '" + from + "' to '" + to + "': a set called '" + to + "' exists");
    }
  }
  for (auto* sets : {element ? &elementSets_ : nullptr, vertex ? &vertexSets_ : nullptr}) {
    if (sets == nullptr) continue;
    auto node = sets->extract(from);
    node.key() = to;
    sets->insert(std::move(node));
  }
}

void TetMesh::setElementSet(const std::string& name, std::vector<int> elements) {
  if (name.empty()) throw ValidationError("element set with an empty name");
  for (int e : elements) {
    if (e < 0 || e >= numElements()) {
      throw ValidationError("element set '" + name + "' lists element " + std::to_string(e) + ", outside [0, " +
                            std::to_string(numElements()) + ")");
    }
  }
  elementSets_[name] = sortedUnique(std::move(elements));
}

void TetMesh::setVertexSet(const std::string& name, std::vector<int> vertices) {
  if (name.empty()) throw ValidationError("vertex set with an empty name");
  for (int v : vertices) {
    if (v < 0 || v >= numVertices()) {
      throw ValidationError("vertex set '" + name + "' lists vertex " + std::to_string(v) + ", outside [0, " +
                            std::to_string(numVertices()) + ")");
    }
  }
  vertexSets_[name] = sortedUnique(std::move(vertices));
}

void TetMesh::setElement(int e, const Eigen::Vector4i& vertices) {
  requireTetrahedra("setElement");
  if (e < 0 || e >= numElements()) throw ValidationError("element " + std::to_string(e) + " out of range");
  for (int a = 0; a < 4; ++a) {
    if (vertices[a] < 0 || vertices[a] >= numVertices()) {
      throw ValidationError("element " + std::to_string(e) + " would reference vertex " + std::to_string(vertices[a]) +
                            ", outside [0, " + std::to_string(numVertices()) + ")");
    }
  }
  elements_.col(e) = vertices;
}

}  // namespace asyncfem
