// SPDX-License-Identifier: BSD-3-Clause
#include "detail/rawMesh.hpp"

#include <Eigen/Dense>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <string>

namespace asyncfem::detail {

Material formatDefaultMaterial() { return Material{"default", 1000.0, 1e6, 0.45}; }

void checkMaterialAt(const LineCursor& cursor, const Material& m) {
  if (!(m.density > 0.0)) cursor.fail("material '" + m.name + "': density must be > 0, got " + formatDouble(m.density));
  if (!(m.youngsModulus > 0.0)) {
    cursor.fail("material '" + m.name + "': Young's modulus must be > 0, got " + formatDouble(m.youngsModulus));
  }
  if (!(m.poissonRatio > -1.0 && m.poissonRatio < 0.5)) {
    cursor.fail("material '" + m.name + "': Poisson's ratio must be in (-1, 0.5), got " + formatDouble(m.poissonRatio));
  }
}

namespace {

int resolveDefaultMaterial(RawMesh& raw, const Material& material, const LineCursor& cursor) {
  for (std::size_t i = 0; i < raw.materials.size(); ++i) {
    if (raw.materials[i].name == material.name) {
      if (raw.materials[i] == material) return static_cast<int>(i);
      cursor.failAtEnd("the default material is called '" + material.name +
                       "' like a different material of the file; rename one of them");
    }
  }
  raw.materials.push_back(material);
  return static_cast<int>(raw.materials.size()) - 1;
}

/// Gives the elements that no region or group covers a material: the caller's default,
/// the format's default (with a warning), or an error naming the first of them.
void assignMissingMaterials(RawMesh& raw, const LineCursor& cursor, const MeshReadOptions& options,
                            MeshReadReport& report, MissingMaterialPolicy policy) {
  const std::size_t numElements = raw.numElements();
  std::size_t firstMissing = numElements;
  for (std::size_t e = 0; e < numElements; ++e) {
    if (raw.elementMaterials[e] < 0) {
      firstMissing = e;
      break;
    }
  }
  if (firstMissing == numElements) return;
  int fallback = -1;
  if (options.defaultMaterial) {
    if (options.defaultMaterial->name.empty()) cursor.failAtEnd("the default material needs a name");
    fallback = resolveDefaultMaterial(raw, *options.defaultMaterial, cursor);
  } else if (policy == MissingMaterialPolicy::FormatDefault) {
    const Material fallbackMaterial = formatDefaultMaterial();
    fallback = resolveDefaultMaterial(raw, fallbackMaterial, cursor);
    report.warnings.push_back(
        "the file has no materials: every element gets the default material '" + fallbackMaterial.name + "' (density " +
        formatDouble(fallbackMaterial.density) + ", E " + formatDouble(fallbackMaterial.youngsModulus) + ", nu " +
        formatDouble(fallbackMaterial.poissonRatio) +
        "); to choose another, override it in the scene (\"materials\": [{\"set\": \"allElements\", "
        "\"density\": ..., \"youngsModulus\": ..., \"poissonRatio\": ...}]), or give meshInfo "
        "--default-material rho,E,nu (MeshReadOptions::defaultMaterial in C++)");
  } else {
    cursor.failAt(raw.elementLocations[firstMissing],
                  "element " + std::to_string(raw.elementFileIds[firstMissing]) +
                      " is covered by no *REGION, so it has no material (add a *REGION line for a set "
                      "containing it, or give a default material)");
  }
  for (int& m : raw.elementMaterials) {
    if (m < 0) m = fallback;
  }
}

/// Element e's vertices, checked against degeneracy and, when options allow, reoriented
/// (last two swapped) if inverted, counted in report.
std::array<int, 4> checkedElement(const RawMesh& raw, std::size_t e, const Eigen::Matrix3Xd& positions,
                                  const LineCursor& cursor, const MeshReadOptions& options, MeshReadReport& report) {
  std::array<int, 4> t = raw.elements[e];
  Eigen::Matrix3d edges;
  const Eigen::Vector3d x0 = positions.col(t[0]);
  for (int a = 0; a < 3; ++a) edges.col(a) = positions.col(t[static_cast<std::size_t>(a + 1)]) - x0;
  const double volume = edges.determinant() / 6.0;
  double edgeSum = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      edgeSum += (positions.col(t[static_cast<std::size_t>(a)]) - positions.col(t[static_cast<std::size_t>(b)])).norm();
  const double meanEdge = edgeSum / 6.0;
  const std::string name = "element " + std::to_string(raw.elementFileIds[e]);
  // <= so that an element whose vertices all coincide (mean edge 0) is degenerate too.
  if (!(std::abs(volume) > options.degenerateVolumeTolerance * meanEdge * meanEdge * meanEdge)) {
    cursor.failAt(raw.elementLocations[e], name + " is degenerate: volume " + formatDouble(volume) +
                                               " with mean edge length " + formatDouble(meanEdge));
  }
  if (volume < 0.0) {
    if (!options.reorientInvertedElements) {
      cursor.failAt(raw.elementLocations[e], name + " is inverted (signed volume " + formatDouble(volume) +
                                                 "); swap two of its vertices or allow reorientation");
    }
    std::swap(t[2], t[3]);
    ++report.reorientedElements;
  }
  return t;
}

/// Counts the vertices no element uses into report, with a warning naming the first.
void reportUnusedVertices(const RawMesh& raw, const std::vector<char>& used, MeshReadReport& report) {
  int unused = 0;
  long long firstUnused = 0;
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) {
      if (unused == 0) firstUnused = raw.vertexFileIds[v];
      ++unused;
    }
  }
  report.unusedVertices = unused;
  if (unused > 0) {
    report.warnings.push_back(std::to_string(unused) + " vertex(es) belong to no element (first: vertex " +
                              std::to_string(firstUnused) +
                              "); they have no mass or stiffness, so a simulation holds them at their rest positions "
                              "(remove them from the file to drop them)");
  }
}

}  // namespace

TetMesh finishMesh(RawMesh raw, const LineCursor& cursor, const MeshReadOptions& options, MeshReadReport& report,
                   MissingMaterialPolicy policy) {
  const std::size_t numElements = raw.numElements();
  const std::size_t numVertices = raw.vertexFileIds.size();
  if (numElements == 0) cursor.failAtEnd("the file has no tetrahedral elements (nor hexahedra)");
  assignMissingMaterials(raw, cursor, options, report, policy);

  Eigen::Matrix3Xd positions(3, static_cast<Eigen::Index>(numVertices));
  for (std::size_t v = 0; v < numVertices; ++v) {
    positions.col(static_cast<Eigen::Index>(v)) =
        Eigen::Vector3d(raw.positions[3 * v], raw.positions[3 * v + 1], raw.positions[3 * v + 2]);
  }
  std::vector<char> used(numVertices, 0);
  Eigen::Matrix4Xi elements;
  HexElements hexahedra;
  if (raw.kind == ElementKind::hexahedron) {
    hexahedra = checkedHexahedra(raw, positions, cursor, options, report);
    for (const int v : hexahedra.reshaped()) used[static_cast<std::size_t>(v)] = 1;
  } else {
    elements.resize(4, static_cast<Eigen::Index>(numElements));
    for (std::size_t e = 0; e < numElements; ++e) {
      const std::array<int, 4> t = checkedElement(raw, e, positions, cursor, options, report);
      for (int a = 0; a < 4; ++a) {
        elements(a, static_cast<Eigen::Index>(e)) = t[static_cast<std::size_t>(a)];
        used[static_cast<std::size_t>(t[static_cast<std::size_t>(a)])] = 1;
      }
    }
  }
  if (report.reorientedElements > 0) {
    report.warnings.push_back("reoriented " + std::to_string(report.reorientedElements) +
                              (raw.kind == ElementKind::hexahedron
                                   ? " inverted hexahedra (negative Jacobian at every corner) by swapping their "
                                     "bottom and top faces"
                                   : " inverted element(s) (negative volume) by swapping their last two vertices"));
  }
  reportUnusedVertices(raw, used, report);

  TetMesh mesh = raw.kind == ElementKind::hexahedron
                     ? TetMesh(std::move(positions), std::move(hexahedra), std::move(raw.materials),
                               std::move(raw.elementMaterials))
                     : TetMesh(std::move(positions), std::move(elements), std::move(raw.materials),
                               std::move(raw.elementMaterials));
  for (auto& [name, members] : raw.elementSets) mesh.setElementSet(name, std::move(members));
  for (auto& [name, members] : raw.vertexSets) mesh.setVertexSet(name, std::move(members));
  return mesh;
}

}  // namespace asyncfem::detail
