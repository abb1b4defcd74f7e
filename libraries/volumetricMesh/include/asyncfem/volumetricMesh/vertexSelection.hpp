// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// Axis-aligned box [min, max] (inclusive) selecting the vertices whose rest position lies in it.
struct VertexBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
};

/// Vertices chosen the ways users name them: sets of either kind (a vertex set, or the
/// vertices of an element set's elements: TetMesh::setVertices), boxes, 0-based ids and a
/// Vega .bou file (1-based ids). The selection is the union of all parts.
struct VertexSelection {
  std::vector<std::string> sets;
  std::vector<VertexBox> boxes;
  std::vector<int> vertices;
  std::optional<std::filesystem::path> bouFile;

  bool empty() const { return sets.empty() && boxes.empty() && vertices.empty() && !bouFile; }
};

/// What selectVertices() rejected, as fields: the part ("sets", "boxes", "vertices",
/// "bou") and its index in that list (-1 for "bou"), so that a caller can name its own
/// key ("fixed.boxes[1]") without reading the message. what() is the bare reason.
class SelectionError : public ValidationError {
 public:
  SelectionError(std::string part, int index, const std::string& message)
      : ValidationError(message), part_(std::move(part)), index_(index) {}
  const std::string& part() const { return part_; }
  int index() const { return index_; }
  /// "sets[2]", "boxes[0]", "vertices[5]", "bou".
  std::string keySuffix() const { return index_ < 0 ? part_ : part_ + "[" + std::to_string(index_) + "]"; }

 private:
  std::string part_;
  int index_;
};

/// The selected vertices, sorted and unique. Throws SelectionError for an unknown set
/// (the message lists the mesh's vertex and element sets), an empty set, a box with
/// min > max or selecting no vertex, an id out of range, and an unreadable or invalid
/// .bou file.
std::vector<int> selectVertices(const TetMesh& mesh, const VertexSelection& selection);

}  // namespace asyncfem
