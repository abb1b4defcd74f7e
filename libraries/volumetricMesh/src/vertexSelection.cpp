// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <map>

namespace asyncfem {

namespace {

template <typename Sets>
std::string setNames(const Sets& sets) {
  std::string names;
  for (const auto& [name, members] : sets) names += (names.empty() ? "" : ", ") + name;
  return names.empty() ? "none" : names;
}

/// Appends the vertices of the named sets (of either kind) to selected.
void appendSetVertices(const TetMesh& mesh, const std::vector<std::string>& sets, std::vector<int>& selected) {
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const std::string& name = sets[i];
    if (!mesh.vertexSets().count(name) && !mesh.elementSets().count(name)) {
      throw SelectionError("sets", static_cast<int>(i),
                           "unknown set \"" + name + "\" (vertex sets: " + setNames(mesh.vertexSets()) +
                               "; element sets: " + setNames(mesh.elementSets()) +
                               "); vertex sets come from Gmsh physical surfaces, curves and points, TetGen .face "
                               "markers (marker_<k>) and .veg *VERTEXSET, element sets from Gmsh physical volumes, "
                               "TetGen regions and .veg *SET (docs/file-formats.md)");
    }
    const std::vector<int> members = mesh.setVertices(name);
    if (members.empty()) throw SelectionError("sets", static_cast<int>(i), "set \"" + name + "\" is empty");
    selected.insert(selected.end(), members.begin(), members.end());
  }
}

/// Appends the vertices whose rest position lies in each box to selected.
void appendBoxVertices(const TetMesh& mesh, const std::vector<VertexBox>& boxes, std::vector<int>& selected) {
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    const VertexBox& box = boxes[b];
    if (!(box.min.array() <= box.max.array()).all()) {
      throw SelectionError("boxes", static_cast<int>(b), "expected min <= max");
    }
    std::size_t count = 0;
    for (int v = 0; v < mesh.numVertices(); ++v) {
      const Eigen::Vector3d x = mesh.restPosition(v);
      if ((x.array() >= box.min.array()).all() && (x.array() <= box.max.array()).all()) {
        selected.push_back(v);
        ++count;
      }
    }
    if (count == 0) throw SelectionError("boxes", static_cast<int>(b), "selects no vertex");
  }
}

}  // namespace

std::vector<int> selectVertices(const TetMesh& mesh, const VertexSelection& selection) {
  std::vector<int> selected;
  appendSetVertices(mesh, selection.sets, selected);
  appendBoxVertices(mesh, selection.boxes, selected);
  for (std::size_t k = 0; k < selection.vertices.size(); ++k) {
    const int v = selection.vertices[k];
    if (v < 0 || v >= mesh.numVertices()) {
      throw SelectionError("vertices", static_cast<int>(k),
                           "vertex " + std::to_string(v) + " out of range [0, " + std::to_string(mesh.numVertices()) +
                               ") (ids are 0-based)");
    }
    selected.push_back(v);
  }
  if (selection.bouFile) {
    std::vector<int> fromFile;
    try {
      fromFile = readBou(*selection.bouFile, mesh.numVertices());
    } catch (const Error& error) {
      throw SelectionError("bou", -1, error.what());
    }
    selected.insert(selected.end(), fromFile.begin(), fromFile.end());
  }
  std::sort(selected.begin(), selected.end());
  selected.erase(std::unique(selected.begin(), selected.end()), selected.end());
  return selected;
}

}  // namespace asyncfem
